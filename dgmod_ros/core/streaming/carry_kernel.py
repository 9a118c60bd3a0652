# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled pass of the background refit: each pixel's weighted normal equations.

:func:`~dgmod_ros.core.streaming.solve_resolution.carry_backgrounds` fits
every full-size pixel's time series on the solve's ``r`` temporal factors
``V`` (m x r) with the entries the solve called foreground weighted out.
Its sums ``G_i = sum_j w_ij v_j v_j^T`` and ``b_i = sum_j w_ij d_ij v_j``
are one pass over the window here, frame by frame along its contiguous
rows (the window is frames-major in memory,
:meth:`~dgmod_ros.core.streaming.results.WindowSnapshot.window`), threaded
over blocks of pixels; as BLAS products the same sums read the window and
the weights several times and cost about three times as much.
Importing :mod:`dgmod_ros.core.kernels` first makes its process-wide numba
settings (cache folder, ``threadsafe`` threading layer) hold here too.
"""

from numba import njit, prange
import numpy as np

# numba's cache folder and threading layer, set before the decorators below run;
# and the solver's pixel blocks.
from ..kernels import _BLOCK_PIXELS

_FAST = {'reassoc', 'contract', 'nsz'}


@njit(parallel=True, cache=True, nogil=True, fastmath=_FAST)
def _normal_equations(frames, channel, weights, temporal, gram, rhs):
    m, _, n = frames.shape
    r = temporal.shape[1]
    block = _BLOCK_PIXELS
    for b in prange((n + block - 1) // block):
        lo = b * block
        hi = min(n, lo + block)
        weighted = np.empty(hi - lo, dtype=np.float32)
        for j in range(m):
            w = weights[j, lo:hi]
            d = frames[j, channel, lo:hi]
            for i in range(hi - lo):
                weighted[i] = w[i] * d[i]
            for a in range(r):
                va = temporal[j, a]
                row = rhs[a, lo:hi]
                for i in range(hi - lo):
                    row[i] += va * weighted[i]
                for c in range(a, r):
                    vac = va * temporal[j, c]
                    row = gram[a, c, lo:hi]
                    for i in range(hi - lo):
                        row[i] += vac * w[i]


def normal_equations(frames, channel, weights, temporal):
    """
    Return each pixel's ``G`` (r, r, n) and ``b`` (r, n) of one channel's weighted fit.

    Parameters
    ----------
    frames : ndarray (m, C, n) float32
        The window frame by frame (C-ordered: no copy for a snapshot's
        stacked columns; any other order is copied).
    channel : int
        The channel fitted.
    weights : ndarray (m, n) float32
        Each entry's weight (1 observed, 0 held out).
    temporal : ndarray (m, r) float32
        The temporal factors ``V``.

    """
    frames = np.ascontiguousarray(frames, dtype=np.float32)
    weights = np.ascontiguousarray(weights, dtype=np.float32)
    temporal = np.ascontiguousarray(temporal, dtype=np.float32)
    r, n = temporal.shape[1], frames.shape[2]
    gram = np.zeros((r, r, n), dtype=np.float32)
    rhs = np.zeros((r, n), dtype=np.float32)
    _normal_equations(frames, int(channel), weights, temporal, gram, rhs)
    for a in range(r):                  # the pass fills the upper triangle
        gram[a + 1:, a] = gram[a, a + 1:]
    return gram, rhs


def compile_kernel():
    """Compile (or load from the cache) the pass on a tiny input."""
    normal_equations(np.ones((4, 3, 5), dtype=np.float32), 0, np.ones((4, 5), dtype=np.float32),
                     np.ones((4, 2), dtype=np.float32))
