# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The spatial graph's squared neighbour differences of a window in one compiled pass.

:func:`~dgmod_ros.core.graphs.spatial_laplacian_bands` weighs each edge of the
4-neighbour pixel graph by the squared difference of the two pixels summed
over the window's frames. In numpy that is a difference image per direction
and an ``einsum`` over the frame axis, whose stride is the window's length,
at every solve and for every channel (docs/solver.md has the cost).
:func:`neighbour_square_sums` reads each frame once, row by
contiguous row, and adds the frames in their order in float32, as the
``einsum`` did on the fused solver's window: there, the same sums bit for
bit as its numpy reference :func:`neighbour_square_sums_reference`
(``test/test_compiled_passes.py``).
numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`; the pass is serial and ``nogil``.
"""

import numpy as np

from ..numba_setup import njit, register_pass


@njit(cache=True, nogil=True)
def _neighbour_square_sums(frames, right, down):
    rows, cols = frames.shape[1], frames.shape[2]
    right[:] = 0.0
    down[:] = 0.0
    for k in range(frames.shape[0]):
        for r in range(rows):
            row = frames[k, r]
            across = right[r]
            for c in range(cols - 1):
                gap = row[c + 1] - row[c]
                across[c] += gap * gap
            if r + 1 < rows:
                below = frames[k, r + 1]
                along = down[r]
                for c in range(cols):
                    gap = below[c] - row[c]
                    along[c] += gap * gap


def neighbour_square_sums(frames):
    """
    Return the squared differences of horizontal and vertical neighbours, summed over frames.

    ``frames`` is a window frames-major, (m, rows, cols) float32. Returns
    ``right`` (rows, cols - 1), the sums between each pixel and the one to
    its right, and ``down`` (rows - 1, cols), between each pixel and the one
    below it.
    """
    frames = np.ascontiguousarray(frames, dtype=np.float32)
    _, rows, cols = frames.shape
    right = np.empty((rows, max(cols - 1, 0)), dtype=np.float32)
    down = np.empty((max(rows - 1, 0), cols), dtype=np.float32)
    _neighbour_square_sums(frames, right, down)
    return right, down


def neighbour_square_sums_reference(frames):
    """Return the sums of :func:`neighbour_square_sums` in numpy, a difference image per frame."""
    frames = np.asarray(frames, dtype=np.float32)
    across = np.diff(frames, axis=2)
    along = np.diff(frames, axis=1)
    right = np.zeros(across.shape[1:], dtype=np.float32)
    down = np.zeros(along.shape[1:], dtype=np.float32)
    for k in range(frames.shape[0]):            # float32 sums over the frames in their order
        right += across[k] * across[k]
        down += along[k] * along[k]
    return right, down


def _examples():
    """Return windows of one and of seven frames, and the degenerate frame shapes."""
    rng = np.random.default_rng(0)
    return [(rng.uniform(0, 1, (m, rows, cols)).astype(np.float32),)
            for m, rows, cols in ((1, 20, 30), (7, 20, 30), (11, 1, 9), (11, 9, 1), (11, 1, 1))]


register_pass(neighbour_square_sums, _examples, reference=neighbour_square_sums_reference)
