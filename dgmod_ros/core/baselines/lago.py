# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""LAGO: fastRPCA's Lagrangian RPCA by the quasi-Newton S-L-S proximal iteration."""

import numpy as np

from .proximal import quasi_newton_sls, singular_value_threshold
from ..linalg import gram_eigh, shrink
from ..window_data import check_window_data


class LAGO:
    r"""
    Lagrangian robust PCA as in fastRPCA's ``solver_RPCA_Lagrangian``.

    .. math:: \min_{L,S} \tfrac12 \|L + S - D\|_F^2 + \lambda_L \|L\|_* + \lambda_S \|S\|_1

    by the quasi-Newton S-L-S proximal iteration with step 0.8, exact singular
    value thresholding (thin SVD through the Gram matrix instead of fastRPCA's
    randomized SVD), zero start.

    Parameters
    ----------
    lambda_l : float, default=0.451
        Nuclear-norm weight: fastRPCA's escalator demo value 115 for data in
        [0, 255], divided by 255 for data in [0, 1].
    lambda_s : float or None, default=None
        l1 weight; None: ``lambda_l / sqrt(max(n, m))``, which gives the demo's
        0.8 / 255 on the escalator video (20800 pixels).
    tol : float, default=1e-6
        Relative change of ``||L + S - D||_F`` that stops the iteration.
        fastRPCA's default for video-sized problems (1e-3) stops on a
        high-rank early iterate (``docs/evaluation.md``).
    max_iter : int, default=200
        fastRPCA's iteration limit for video-sized problems.

    References
    ----------
    .. [1] A. Aravkin, S. Becker, V. Cevher, P. Olsen, "A variational approach
       to stable principal component pursuit", UAI 2014 (fastRPCA).

    """

    def __init__(self, lambda_l=0.451, lambda_s=None, tol=1e-6, max_iter=200):
        self.lambda_l = lambda_l
        self.lambda_s = lambda_s
        self.tol = tol
        self.max_iter = max_iter

    def fit(self, data, frame_shape, init=None):
        """Separate one window (n pixels x m frames); ``init`` is unused."""
        data = check_window_data(data, frame_shape)
        lambda_s = (self.lambda_s if self.lambda_s is not None
                    else self.lambda_l / np.sqrt(max(data.shape)))
        if not (self.lambda_l > 0 and lambda_s > 0):
            raise ValueError('lambda_l and lambda_s must be positive')
        zeros = np.zeros_like(data)
        low_rank, sparse, self.n_iter_, converged, self.rank_ = quasi_newton_sls(
            data, lambda x, t: singular_value_threshold(x, t * self.lambda_l),
            lambda x, t: shrink(x, t * lambda_s), zeros, zeros, self.tol, self.max_iter)
        self.lambda_s_ = lambda_s
        self.info_ = 0 if converged else self.n_iter_
        self.background_, self.foreground_ = low_rank, sparse
        self.objective_ = float(0.5 * np.linalg.norm(low_rank + sparse - data) ** 2
                                + self.lambda_l * _nuclear_norm(low_rank)
                                + lambda_s * np.abs(sparse).sum())
        return self


def _nuclear_norm(matrix):
    return float(gram_eigh(matrix, vectors=False).sum())
