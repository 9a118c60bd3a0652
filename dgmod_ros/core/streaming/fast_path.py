# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The per-frame fast path: a frame's foreground magnitude from the last window solve.

A frame is projected robustly (iteratively reweighted least squares for an l1
fit) onto the background subspace of the last solve; the residual is the
foreground. Before the first solve the per-pixel median of the buffered
frames is the background.
"""

import numpy as np

from .kernels.fast_path import (irls_weights, weighted_normal_equations,
                                weighted_normal_equations_reference)
from ..linalg import thin_svd

# IRLS sweeps of the l1 projection; residual changes are below 1e-3 after
# three on the test scenes.
_IRLS_SWEEPS = 3
# Smallest residual an IRLS weight is taken from (a tenth of a grey level of 8-bit data).
_IRLS_FLOOR = 1e-3
# Relative singular-value cut-off of the background basis.
_BASIS_RTOL = 1e-3
# Most pixels the IRLS sweeps weigh: the fit has basis_rank unknowns a
# channel, which a regular sample of the frame's pixels fixes as well as all
# of them (docs/node.md has the measured effect); the projection itself is
# of every pixel. 160 x 120, a 640 x 480 camera's frame at scale 0.25.
FIT_PIXELS = 19200


def fit_step(pixels, fit_pixels=None):
    """Return the stride of the pixel sample the IRLS sweeps weigh (1: every pixel)."""
    return max(1, int(pixels) // int(FIT_PIXELS if fit_pixels is None else fit_pixels))


def background_basis(background, max_rank=None):
    """Return an orthonormal basis of the dominant column space of a background (n x m)."""
    left, _, _ = thin_svd(np.asarray(background, dtype=np.float32), max_rank, _BASIS_RTOL)
    return left


def sampled_basis(basis, fit_pixels=None):
    """
    Return the basis (C, n, r) at the pixels the IRLS sweeps weigh, C-contiguous.

    The same for every frame until the next solve, which therefore forms it
    once (:attr:`~.results.BackgroundModel.fit_basis`) instead of each frame.
    """
    basis = np.ascontiguousarray(basis, dtype=np.float32)
    step = fit_step(basis.shape[1], fit_pixels)
    return basis if step == 1 else np.ascontiguousarray(basis[:, ::step])


def irls(coef, normal_equations, solve):
    """
    Return the coefficients after the IRLS sweeps from ``coef``: the one loop of every l1 fit here.

    Each sweep forms the normal equations weighted by the current residual
    (``normal_equations(coef)``, weights
    :func:`~dgmod_ros.core.streaming.kernels.fast_path.irls_weights`) and
    solves them (``solve(gram, rhs)``).
    """
    for _ in range(_IRLS_SWEEPS):
        coef = solve(*normal_equations(coef))
    return coef


def robust_projection(basis, columns, fit_pixels=None, fit_basis=None, left_out=None):
    """
    l1-fit each channel's column onto its basis by IRLS; return the fitted columns.

    Each sweep's weighted normal equations are formed in one compiled pass
    (:func:`~dgmod_ros.core.streaming.kernels.fast_path.weighted_normal_equations`,
    float64 sums) instead of five numpy passes. The sweeps start from the
    least-squares coefficients of every pixel and weigh every
    ``fit_step``-th pixel only; the returned projection is of every pixel.

    Parameters
    ----------
    basis : ndarray (C, n, r)
        Orthonormal background basis of each channel.
    columns : ndarray (C, n)
        One frame, one column per channel.
    fit_pixels : int or None
        Most pixels the sweeps weigh; None: ``FIT_PIXELS``.
    fit_basis : ndarray or None
        ``sampled_basis(basis, fit_pixels)`` where the caller keeps it; None forms it.
    left_out : ndarray (n,) bool or None
        Pixels the fit leaves out (the previous frame's foreground), unless
        fewer than a tenth of the sample would remain: an l1 fit breaks
        down once a person covers about half of the view (its start sooner:
        least squares over a person covering 40 % is pulled towards them),
        and the whole frame then reads as changed. None: every pixel.

    """
    return _robust_projection(basis, columns, fit_pixels, fit_basis, weighted_normal_equations,
                              left_out)


def robust_projection_reference(basis, columns, fit_pixels=None):
    """Return :func:`robust_projection` with numpy's normal equations (the tests' reference)."""
    return _robust_projection(basis, columns, fit_pixels, None,
                              weighted_normal_equations_reference)


def _robust_projection(basis, columns, fit_pixels, fit_basis, equations, left_out=None):
    basis = np.ascontiguousarray(basis, dtype=np.float32)
    columns = np.ascontiguousarray(columns, dtype=np.float32)
    channels, n, rank = basis.shape
    gram = np.empty((channels, rank, rank))
    rhs = np.empty((channels, rank))
    step = fit_step(n, fit_pixels)
    if fit_basis is None:
        fit_basis = sampled_basis(basis, fit_pixels)
    fit_columns = columns if step == 1 else np.ascontiguousarray(columns[:, ::step])

    # The sweeps read fit_basis and fit_columns when called: after the kept pixels' choice below.
    def normal_equations(coef):
        equations(fit_basis, fit_columns, coef, _IRLS_FLOOR, gram, rhs)
        return gram, rhs

    def solve(gram, rhs):
        return np.stack([np.linalg.lstsq(gram[channel], rhs[channel], rcond=None)[0]
                         for channel in range(channels)])

    kept = None if left_out is None else ~np.asarray(left_out, dtype=bool)[::step]
    # Too few pixels left to fix the fit: the whole frame's.
    if kept is not None and np.count_nonzero(kept) >= max(16, kept.size // 10):
        fit_basis = np.ascontiguousarray(fit_basis[:, kept])
        fit_columns = np.ascontiguousarray(fit_columns[:, kept])
        # Least squares over the kept pixels, where the basis is not orthonormal.
        start = np.matmul(fit_columns[:, None, :], fit_basis)[:, 0, :].astype(np.float64)
        coef = solve(np.matmul(fit_basis.transpose(0, 2, 1), fit_basis).astype(np.float64),
                     start)
    else:
        coef = np.matmul(columns[:, None, :], basis)[:, 0, :].astype(np.float64)
    coef = irls(coef, normal_equations, solve)
    return np.matmul(basis, coef.astype(np.float32)[:, :, None])[:, :, 0]


def projection_residual(basis, data, robust=True):
    """
    Return each window column's residual against its projection on the basis.

    The residual the per-frame decision thresholds is a frame minus its
    :func:`robust_projection`; this gives the window's own columns the same
    residual, all columns at once (one small r x r system per column).

    Parameters
    ----------
    basis : ndarray (C, n, r)
        Orthonormal background basis of each channel (zero columns: unused).
    data : ndarray (C, n, m)
        The window's columns.
    robust : bool
        l1 fit by IRLS as :func:`robust_projection`; False: least squares.

    """
    residual = np.empty_like(data)
    step = fit_step(data.shape[1])          # the sweeps' pixel sample, as robust_projection's
    for channel in range(data.shape[0]):
        used = np.any(basis[channel] != 0, axis=0)
        b, d = basis[channel][:, used], data[channel]                # (n, r), (n, m)
        coef = b.T @ d                                                # (r, m)
        if robust:
            rank = b.shape[1]
            b_fit, d_fit = b[::step], d[::step]
            products = (b_fit[:, :, None] * b_fit[:, None, :]).reshape(b_fit.shape[0],
                                                                       rank * rank)

            def normal_equations(coef):
                # Every column's system at once: (m, r, r) and (m, r, 1).
                weights = irls_weights(d_fit - b_fit @ coef, _IRLS_FLOOR)
                return ((products.T @ weights).T.reshape(-1, rank, rank),
                        (b_fit.T @ (weights * d_fit)).T[..., None])

            coef = irls(coef, normal_equations,
                        lambda gram, right: np.linalg.solve(gram, right)[..., 0].T)
        residual[channel] = d - b @ coef
    return residual
