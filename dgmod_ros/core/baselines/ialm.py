# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Classical principal component pursuit by the inexact augmented Lagrangian method."""

import numpy as np

from .proximal import singular_value_threshold
from ..linalg import shrink, top_singular_value
from ..window_data import check_window_data


class InexactALM:
    r"""
    PCP (Candes, Li, Ma, Wright 2011) by inexact ALM (Lin, Chen, Ma 2010).

    .. math:: \min_{L,S} \|L\|_* + \lambda \|S\|_1 \ \text{s.t.}\ L + S = D

    with ``lambda = 1 / sqrt(max(n, m))``, ``Y0 = D / max(||D||_2, ||D||_inf / lambda)``,
    ``mu0 = 1.25 / ||D||_2`` growing by ``rho = 1.5`` per iteration up to ``1e7 mu0``.

    Parameters
    ----------
    lam : float or None, default=None
        None: ``1 / sqrt(max(n, m))``.
    tol : float, default=1e-7
        Stop when ``||D - L - S||_F / ||D||_F < tol``.
    max_iter : int, default=500
        Iterations at most.

    References
    ----------
    .. [1] E. Candes, X. Li, Y. Ma, J. Wright, "Robust principal component
       analysis?", Journal of the ACM 58(3), 2011.
    .. [2] Z. Lin, M. Chen, Y. Ma, "The augmented Lagrange multiplier method for
       exact recovery of corrupted low-rank matrices", arXiv:1009.5055, 2010.

    """

    def __init__(self, lam=None, tol=1e-7, max_iter=500):
        self.lam = lam
        self.tol = tol
        self.max_iter = max_iter

    def fit(self, data, frame_shape, init=None):
        """Separate one window (n pixels x m frames); ``init`` is unused."""
        data = check_window_data(data, frame_shape)
        lam = self.lam if self.lam is not None else 1.0 / np.sqrt(max(data.shape))
        norm_two = top_singular_value(data)
        norm_fro = float(np.linalg.norm(data)) or 1.0
        dual = data / max(norm_two, float(np.abs(data).max()) / lam, 1e-30)
        mu = 1.25 / max(norm_two, 1e-30)
        mu_max = mu * 1e7
        sparse = np.zeros_like(data)
        self.info_ = self.max_iter
        for iteration in range(1, self.max_iter + 1):
            low_rank, self.rank_ = singular_value_threshold(data - sparse + dual / mu, 1.0 / mu)
            sparse = shrink(data - low_rank + dual / mu, lam / mu)
            residual = data - low_rank - sparse
            dual += mu * residual
            mu = min(mu * 1.5, mu_max)
            if np.linalg.norm(residual) / norm_fro < self.tol:
                self.info_ = 0
                break
        self.n_iter_ = iteration
        self.lam_ = lam
        self.background_, self.foreground_ = low_rank, sparse
        return self
