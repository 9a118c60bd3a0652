# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled pass of the fast path's l1 projection (one IRLS sweep's normal equations).

numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
The pass is serial and ``nogil``: it runs in the image callback while the solve
thread's kernels own the cores, and a frame's few hundred thousand entries
are less work than starting threads.
"""

import numpy as np

from ...numba_setup import FAST_MATH, njit, register_pass


# The passes' flags and reciprocals (the weights are ones over the residuals).
_FAST_ARCP = FAST_MATH | {'arcp'}


@njit(cache=True, nogil=True, fastmath=_FAST_ARCP)
def _rank2_equations(basis, columns, coef, floor, gram, rhs):
    # The default basis_rank spelled out: scalar sums the compiler vectorises.
    for c in range(basis.shape[0]):
        c0 = np.float32(coef[c, 0])
        c1 = np.float32(coef[c, 1])
        g00 = g01 = g11 = r0 = r1 = 0.0
        for i in range(basis.shape[1]):
            b0 = basis[c, i, 0]
            b1 = basis[c, i, 1]
            d = columns[c, i]
            weight = np.float32(1.0) / max(abs(d - b0 * c0 - b1 * c1), np.float32(floor))
            w0 = weight * b0
            w1 = weight * b1
            g00 += w0 * b0
            g01 += w0 * b1
            g11 += w1 * b1
            r0 += w0 * d
            r1 += w1 * d
        gram[c, 0, 0] = g00
        gram[c, 0, 1] = gram[c, 1, 0] = g01
        gram[c, 1, 1] = g11
        rhs[c, 0] = r0
        rhs[c, 1] = r1


@njit(cache=True, nogil=True, fastmath=_FAST_ARCP)
def _rank1_equations(basis, columns, coef, floor, gram, rhs):
    # A still scene's background has rank 1.
    for c in range(basis.shape[0]):
        c0 = np.float32(coef[c, 0])
        g00 = r0 = 0.0
        for i in range(basis.shape[1]):
            b0 = basis[c, i, 0]
            d = columns[c, i]
            w0 = b0 / max(abs(d - b0 * c0), np.float32(floor))
            g00 += w0 * b0
            r0 += w0 * d
        gram[c, 0, 0] = g00
        rhs[c, 0] = r0


@njit(cache=True, nogil=True, fastmath=_FAST_ARCP)
def _any_rank_equations(basis, columns, coef, floor, gram, rhs):
    channels, n, rank = basis.shape
    for c in range(channels):
        gram[c] = 0.0
        rhs[c] = 0.0
        for i in range(n):
            fitted = np.float32(0.0)
            for a in range(rank):
                fitted += basis[c, i, a] * np.float32(coef[c, a])
            weight = np.float32(1.0) / max(abs(columns[c, i] - fitted), np.float32(floor))
            for a in range(rank):
                weighted = weight * basis[c, i, a]
                rhs[c, a] += weighted * columns[c, i]
                for b in range(a, rank):
                    gram[c, a, b] += weighted * basis[c, i, b]
        for a in range(rank):
            for b in range(a):
                gram[c, a, b] = gram[c, b, a]


def weighted_normal_equations(basis, columns, coef, floor, gram, rhs):
    """
    Form each channel's IRLS normal equations for the l1 fit of ``columns`` on ``basis``.

    With the residual ``e = columns - basis @ coef`` and weights
    ``w = 1 / max(|e|, floor)`` (float32, as the numpy formulation), writes
    ``gram[c] = B^T W B`` and ``rhs[c] = B^T W d`` (float64 sums) for every
    channel ``c``.

    Parameters
    ----------
    basis : ndarray (C, n, r) float32, C-contiguous
        Each channel's background basis.
    columns : ndarray (C, n) float32, C-contiguous
        The frame, one column per channel.
    coef : ndarray (C, r) float64
        The current coefficients.
    floor : float
        Smallest residual a weight is taken from.
    gram : ndarray (C, r, r) float64
        Output.
    rhs : ndarray (C, r) float64
        Output.

    """
    kernel = {1: _rank1_equations, 2: _rank2_equations}.get(basis.shape[2], _any_rank_equations)
    kernel(basis, columns, coef, floor, gram, rhs)


def irls_weights(residual, floor):
    """Return the IRLS weights ``1 / max(|e|, floor)`` of an l1 fit's residual ``e``."""
    return 1.0 / np.maximum(np.abs(residual), floor)


def weighted_normal_equations_reference(basis, columns, coef, floor, gram, rhs):
    """Compute :func:`weighted_normal_equations` in numpy (BLAS sums, in another order)."""
    fitted = np.matmul(basis, coef.astype(np.float32)[:, :, None])[:, :, 0]
    weighted = (irls_weights(columns - fitted, np.float32(floor))[:, :, None]
                * basis).astype(np.float64)                                  # (C, n, r)
    gram[:] = np.matmul(weighted.transpose(0, 2, 1), basis)
    rhs[:] = np.matmul(weighted.transpose(0, 2, 1), columns[:, :, None])[:, :, 0]


def _examples():
    """Return a frame's fit at ranks 1 (a still scene), 2 (the default) and 3 (any other)."""
    rng = np.random.default_rng(0)
    examples = []
    for rank in (1, 2, 3):
        basis = rng.normal(0, 0.05, (3, 400, rank)).astype(np.float32)
        columns = rng.uniform(0, 1, (3, 400)).astype(np.float32)
        examples.append((basis, columns, rng.normal(0, 1, (3, rank)), 1e-3,
                         np.empty((3, rank, rank)), np.empty((3, rank))))
    return examples


# Float32 products summed in float64 in another order (fastmath reassociates).
register_pass(weighted_normal_equations, _examples, weighted_normal_equations_reference,
              atol=1e-6, rtol=1e-5)
