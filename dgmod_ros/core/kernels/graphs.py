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
bit (``test/test_graphs.py``).
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


register_pass(neighbour_square_sums,
              lambda: [(np.random.default_rng(0).uniform(0, 1, (m, 20, 30)).astype(np.float32),)
                       for m in (1, 7)])
