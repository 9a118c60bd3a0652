# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled pass of the fast path's l1 projection (one IRLS sweep's normal equations).

Importing :mod:`dgmod_ros.core.kernels` first makes its process-wide numba
settings (cache folder, ``threadsafe`` threading layer) hold here too. The
pass is serial and ``nogil``: it runs in the image callback while the solve
thread's kernels own the cores, and a frame's few hundred thousand entries
are less work than starting threads.

The sums are float64 and run pixel after pixel: their order fixes the
projection's last bits, and with them the masks. The rank-2 pass (the
default) keeps that order and still vectorises the work per pixel: it forms
a block of pixels' products in one vectorised loop and adds them in order in
a second (:func:`_rank2_equations`), about twice as fast as the one scalar
loop it replaces (:func:`_rank2_equations_serial`, kept as the reference the
tests hold it to bit for bit).
"""

from numba import njit
import numpy as np

# numba's cache folder and threading layer, set before the decorators below run.
from .. import kernels  # noqa: F401


# Reassociation lets the compiler vectorise the sums over pixels; no 'nnan':
# a non-finite frame must stay visible.
_FAST = {'reassoc', 'contract', 'nsz', 'arcp'}


# Pixels per block of the rank-2 pass: its products (5 x 3 x 4 bytes a pixel) stay in L1.
_BLOCK = 1024


@njit(cache=True, nogil=True, fastmath=_FAST, error_model='numpy')
def _rank2_products(first, second, column, c0, c1, floor, products):
    """
    Write one block's five IRLS products of one channel (vectorised).

    The expressions and flags of :func:`_rank2_equations_serial`, so the
    compiler makes the same float32 operations (fused or not) of them; the
    floor is positive, so the division never meets the zero that the
    default error model checks for (the check kept the loop scalar).
    """
    for j in range(column.shape[0]):
        b0 = first[j]
        b1 = second[j]
        d = column[j]
        weight = np.float32(1.0) / max(abs(d - b0 * c0 - b1 * c1), floor)
        w0 = weight * b0
        w1 = weight * b1
        products[0, j] = w0 * b0
        products[1, j] = w0 * b1
        products[2, j] = w1 * b1
        products[3, j] = w0 * d
        products[4, j] = w1 * d


@njit(cache=True, nogil=True)
def _add_in_order(products, count, sums):
    """Add a block's products to the five float64 sums, pixel after pixel (no reassociation)."""
    s0, s1, s2, s3, s4 = sums[0], sums[1], sums[2], sums[3], sums[4]
    for j in range(count):
        s0 += products[0, j]
        s1 += products[1, j]
        s2 += products[2, j]
        s3 += products[3, j]
        s4 += products[4, j]
    sums[0], sums[1], sums[2], sums[3], sums[4] = s0, s1, s2, s3, s4


@njit(cache=True, nogil=True)
def _rank2_equations(planes, columns, coef, floor, gram, rhs):
    # The default basis_rank, in blocks: the products vectorised, then added
    # in pixel order, so the sums are :func:`_rank2_equations_serial`'s bit for bit.
    channels, _, n = planes.shape
    products = np.empty((5, _BLOCK), dtype=np.float32)
    sums = np.empty(5)
    for c in range(channels):
        c0 = np.float32(coef[c, 0])
        c1 = np.float32(coef[c, 1])
        sums[:] = 0.0
        for start in range(0, n, _BLOCK):
            stop = min(start + _BLOCK, n)
            _rank2_products(planes[c, 0, start:stop], planes[c, 1, start:stop],
                            columns[c, start:stop], c0, c1, np.float32(floor), products)
            _add_in_order(products, stop - start, sums)
        gram[c, 0, 0] = sums[0]
        gram[c, 0, 1] = gram[c, 1, 0] = sums[1]
        gram[c, 1, 1] = sums[2]
        rhs[c, 0] = sums[3]
        rhs[c, 1] = sums[4]


@njit(cache=True, nogil=True, fastmath=_FAST)
def _rank2_equations_serial(basis, columns, coef, floor, gram, rhs):
    # The rank-2 pass as it was before the blocks (one scalar loop): the
    # compiled reference the tests hold :func:`_rank2_equations` to, bit for bit.
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


@njit(cache=True, nogil=True, fastmath=_FAST)
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


@njit(cache=True, nogil=True, fastmath=_FAST)
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


def weighted_normal_equations(basis, columns, coef, floor, gram, rhs, planes=None):
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
    planes : ndarray (C, r, n) float32, C-contiguous, or None
        ``basis`` with each component contiguous (:func:`basis_planes`), for
        rank 2; None: made here.

    """
    rank = basis.shape[2]
    if rank == 2:
        _rank2_equations(basis_planes(basis) if planes is None else planes, columns, coef,
                         floor, gram, rhs)
        return
    kernel = _rank1_equations if rank == 1 else _any_rank_equations
    kernel(basis, columns, coef, floor, gram, rhs)


def basis_planes(basis):
    """Return ``basis`` (C, n, r) as (C, r, n), each component contiguous (the rank-2 input)."""
    return np.ascontiguousarray(np.transpose(basis, (0, 2, 1)))


def compile_kernel():
    """Compile (or load from the cache) both passes on a tiny input."""
    for rank in (1, 2, 3):
        weighted_normal_equations(np.ones((1, 4, rank), dtype=np.float32),
                                  np.ones((1, 4), dtype=np.float32), np.zeros((1, rank)),
                                  1e-3, np.empty((1, rank, rank)), np.empty((1, rank)))
