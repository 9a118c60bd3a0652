# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Fused, multi-threaded kernels of one ADMM sweep of :class:`DualGraphMOD`.

A sweep of the numpy formulation is about 25 single-threaded passes over
``n x m`` float32 arrays. Here it is one pass, threaded over blocks of pixel
rows (:func:`primal_pass`): the gradient L-step (spatial and temporal
Laplacians applied as diagonal bands), the S- and V-shrinkages, the dual
update of ``Y2``, the next SVT input ``Lh`` and the sums of squares behind the
stopping rule. ``Y1`` is never stored (``Y1 = U - Lh`` after every U-step),
and V, ``Y2`` and ``Lh`` are updated in place, so the pass moves as few
arrays as the sweep needs (docs/solver.md, "Fused sweep").
:func:`squared_gap` gives the primal residual ``||U - L||`` where the next
pass cannot wait for it.

Between passes the weighted SVT stays with BLAS: the Gram matrix ``Lh^T Lh``
and the rank-k product ``U = (Lh left) right_t`` are dense products that a
hand-written loop does several times slower than sgemm.

Import side effects, all process-wide and made before the first compiled call:

- ``NUMBA_CACHE_DIR`` defaults to ``$XDG_CACHE_HOME/dgmod_ros/numba`` (else
  ``~/.cache/dgmod_ros/numba``) when unset, so an installed package in a
  read-only prefix still loads its compiled kernels from disk instead of
  compiling them at every start;
- ``numba.config.THREADING_LAYER = 'threadsafe'``: the node calls kernels from
  its image callback and its solve thread at once, and numba's ``workqueue``
  fallback stops the process when two threads enter it. ``threadsafe`` makes
  numba take ``tbb`` or ``omp`` (libgomp, which comes with gcc) or fail loudly;
- OpenBLAS runs on one thread (:func:`~dgmod_ros.core.runtime.limit_blas_threads`):
  the kernels own the cores, and OpenBLAS threads spinning beside them made a
  sweep several times slower (docs/solver.md, "Fused sweep").
"""

import os
from pathlib import Path


def default_cache_dir():
    """Return the folder for numba's compiled-kernel cache (see module docstring)."""
    base = os.environ.get('XDG_CACHE_HOME') or str(Path.home() / '.cache')
    return str(Path(base) / 'dgmod_ros' / 'numba')


if not os.environ.get('NUMBA_CACHE_DIR'):
    os.environ['NUMBA_CACHE_DIR'] = default_cache_dir()
# Also in the environment: numba re-reads its whole configuration from the
# environment when that changed since its import (the line above does, when
# another module imported numba first), which would reset an attribute set alone.
os.environ.setdefault('NUMBA_THREADING_LAYER', 'threadsafe')

import numba  # noqa: E402 (the cache folder must be set before numba reads its config)
from numba import njit, prange  # noqa: E402
import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402

from .runtime import limit_blas_threads  # noqa: E402

if not numba.config.CACHE_DIR:      # numba was imported before this module
    numba.config.CACHE_DIR = os.environ['NUMBA_CACHE_DIR']
numba.config.THREADING_LAYER = 'threadsafe'
limit_blas_threads(1)

# Rows per block of the threaded loops: enough to amortise the per-block
# scratch rows, few enough to balance two to eight threads.
_BLOCK_ROWS = 256


def diagonal_bands(matrix):
    """
    Return ``(offsets, bands)`` with ``matrix[i, i + offsets[k]] == bands[k, i]``.

    ``matrix`` is square (scipy sparse or dense); ``bands`` is float32 of shape
    ``(len(offsets), n)``, zero where ``i + offset`` leaves the matrix. The
    graph Laplacians are banded (4-neighbour pixels in row-major order:
    offsets 0, +-1, +-n2; frames: the temporal reach), so a product with them
    is a few shifted multiply-adds per row that the compiler vectorises.
    """
    coo = sp.coo_matrix(matrix)
    coo.sum_duplicates()
    n = coo.shape[0]
    diff = coo.col.astype(np.int64) - coo.row.astype(np.int64)
    offsets = np.unique(diff)
    bands = np.zeros((offsets.size, n), dtype=np.float32)
    bands[np.searchsorted(offsets, diff), coo.row] = coo.data
    return offsets.astype(np.int64), bands


@njit(cache=True, inline='always')
def _shrink(x, t):
    # x - clip(x, -t, t): branch-free, so the row loops vectorise.
    return x - min(max(x, -t), t)


# Reassociation lets the compiler vectorise the sums of squares; no
# 'nnan'/'ninf': the solver detects a non-finite iterate from those sums.
# nogil: a pass takes milliseconds, and the node's image callback must not
# wait for the solve thread's kernels.
_FAST = {'reassoc', 'contract', 'nsz'}


@njit(parallel=True, cache=True, fastmath=_FAST, nogil=True)
def primal_pass(data, L, U, Lh, S, V, Y2,
                s_offsets, s_bands, t_offsets, t_bands, coefficients, l_given,
                L_new, S_new):
    """
    Run one sweep but the SVT, fused, threaded over row blocks.

    The dual ``Y1`` is not stored: after every U-step ``Y1 = U - Lh`` exactly
    (``Y1 + U - L`` with ``Lh = L - Y1``), so each row reads it from ``U`` and
    the previous ``Lh``. Per row: the L-step (one gradient step into
    ``L_new``; with ``l_given`` the caller computed ``L_new`` in numpy), the
    S-step into ``S_new``, and in place the V-step, ``Y2 += D - L - S - V``
    and the next SVT input ``Lh = L_new - Y1``. ``L`` and ``S`` keep the
    previous iterate (the L-step reads neighbouring rows of ``L``; the solver
    falls back on both when an iterate is not finite). ``coefficients`` =
    (g1, g2, c, rho1, rho2, step, lam2 / rho2, 1 / rho2) as float64.

    Returns the float64 sums ``(||L_new - L||^2, ||L||^2, ||S_new - S||^2,
    ||S||^2, ||U - L||^2, ||D - L_new - S_new - V_new||^2)``: the fifth is the
    previous sweep's primal residual of ``U = L`` (``U`` is that sweep's SVT).
    """
    n, m = data.shape
    g1 = np.float32(coefficients[0])
    g2 = np.float32(coefficients[1])
    c = np.float32(coefficients[2])
    rho1 = np.float32(coefficients[3])
    rho2 = np.float32(coefficients[4])
    step = np.float32(coefficients[5])
    t_s = np.float32(coefficients[6])
    t_v = np.float32(coefficients[7])
    n_blocks = (n + _BLOCK_ROWS - 1) // _BLOCK_ROWS
    sums = np.zeros((n_blocks, 6), dtype=np.float64)
    reach = 0
    for k in range(t_offsets.size):
        reach = max(reach, abs(t_offsets[k]))
    for b in prange(n_blocks):
        spatial = np.empty(m, dtype=np.float32)
        temporal = np.empty(m, dtype=np.float32)
        dual = np.empty(m, dtype=np.float32)
        # One row of L with ``reach`` zeros either side: the temporal bands
        # become fixed-length loops (the bands are zero where j + off leaves
        # the window).
        padded = np.zeros(m + 2 * reach, dtype=np.float32)
        d_l = 0.0
        n_l = 0.0
        d_s = 0.0
        n_s = 0.0
        r_u = 0.0
        r_v = 0.0
        for i in range(b * _BLOCK_ROWS, min(n, (b + 1) * _BLOCK_ROWS)):
            for j in range(m):
                dual[j] = U[i, j] - Lh[i, j]
                gap = U[i, j] - L[i, j]
                r_u += gap * gap
            if not l_given:
                for j in range(m):
                    spatial[j] = 0.0
                    temporal[j] = 0.0
                    padded[reach + j] = L[i, j]
                for k in range(s_offsets.size):
                    row = i + s_offsets[k]
                    if 0 <= row < n:
                        weight = s_bands[k, i]
                        for j in range(m):
                            spatial[j] += weight * L[row, j]
                for k in range(t_offsets.size):
                    # (L Phi_t)[i, j] = sum_k L[i, j + off] Phi_t[j + off, j]
                    #                 = sum_k L[i, j + off] Phi_t[j, j + off] (symmetric).
                    # Unsigned indices: numba's negative-index wraparound
                    # check on a signed index stops this loop vectorising (7x).
                    start = np.uint64(reach + t_offsets[k])
                    for j in range(m):
                        temporal[j] += t_bands[k, j] * padded[start + np.uint64(j)]
                for j in range(m):
                    rhs = rho1 * (U[i, j] + dual[j]) \
                        + rho2 * (data[i, j] - S[i, j] - V[i, j] + Y2[i, j])
                    grad = c * L[i, j] - rhs + g1 * spatial[j] + g2 * temporal[j]
                    L_new[i, j] = L[i, j] - step * grad
            for j in range(m):
                background = L_new[i, j]
                residual = data[i, j] - background
                foreground = _shrink(residual - V[i, j] + Y2[i, j], t_s)
                noise = _shrink(residual - foreground + Y2[i, j], t_v)
                gap = residual - foreground - noise
                Y2[i, j] += gap
                r_v += gap * gap
                S_new[i, j] = foreground
                V[i, j] = noise
                Lh[i, j] = background - dual[j]
                delta = background - L[i, j]
                d_l += delta * delta
                n_l += L[i, j] * L[i, j]
                delta = foreground - S[i, j]
                d_s += delta * delta
                n_s += S[i, j] * S[i, j]
        sums[b, 0] = d_l
        sums[b, 1] = n_l
        sums[b, 2] = d_s
        sums[b, 3] = n_s
        sums[b, 4] = r_u
        sums[b, 5] = r_v
    return sums.sum(axis=0)


@njit(parallel=True, cache=True, fastmath=_FAST, nogil=True)
def squared_gap(a, b):
    """Return ``||a - b||_F^2`` in float64, threaded over row blocks."""
    n = a.shape[0]
    n_blocks = (n + _BLOCK_ROWS - 1) // _BLOCK_ROWS
    sums = np.zeros(n_blocks, dtype=np.float64)
    for blk in prange(n_blocks):
        total = 0.0
        for i in range(blk * _BLOCK_ROWS, min(n, (blk + 1) * _BLOCK_ROWS)):
            for j in range(a.shape[1]):
                gap = a[i, j] - b[i, j]
                total += gap * gap
        sums[blk] = total
    return sums.sum()


def compile_all():
    """
    Compile (or load from the cache) every kernel by running it on a tiny window.

    A cold compile takes tens of seconds on a small machine and holds the GIL;
    run this once after installing (``python3 -c 'from dgmod_ros.core.kernels
    import compile_all; compile_all()'``) so the node starts from the cache.
    """
    from .dgmod import DualGraphMOD
    data = np.linspace(0.0, 1.0, 12 * 4, dtype=np.float32).reshape(12, 4)
    DualGraphMOD(max_iter=1).fit(data, (3, 4))
    DualGraphMOD(max_iter=1, l_step='exact').fit(data, (3, 4))
    from .streaming.irls_kernel import compile_kernel     # the fast path's projection
    compile_kernel()
    from .streaming.mean_field_kernel import compile_kernel as compile_field
    compile_field()                                       # the per-frame decision
    from .streaming.blobs import compile_kernel as compile_blobs
    compile_blobs()                                       # the ghost and still tests
    from .streaming.lighting_kernel import compile_kernel as compile_lighting
    compile_lighting()                                    # the lighting test
