# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Split SPCP: the factorized Lagrangian RPCA of Driggs, Becker and Aravkin, by L-BFGS."""

from dataclasses import dataclass

import numpy as np

from .lbfgs import lbfgs
from ..linalg import drop_oldest, shrink
from ..window_data import check_window_data


@dataclass
class FactorState:
    """The factors ``U`` (n x k) and ``V`` (m x k) of a solution, for a warm start."""

    left: np.ndarray
    right: np.ndarray

    @property
    def frames(self):
        """Return how many frames the factors span (rows of V)."""
        return self.right.shape[0]

    def shifted(self, count):
        """Factors for a window that dropped ``count`` frames (new rows repeat the last)."""
        if count <= 0:
            return self
        return FactorState(self.left, drop_oldest(self.right, count, self.right[-1], axis=0))


class SplitSPCP:
    r"""
    Factorized stable PCP as in fastRPCA's ``solver_split_SPCP``.

    .. math:: \min_{U,V} \tfrac{\lambda_L}{2}(\|U\|_F^2 + \|V\|_F^2)
              + \sum_{ij} \mathrm{huber}_{\lambda_S}\big((D - U V^T)_{ij}\big)

    with ``U`` (n x k), ``V`` (m x k), ``L = U V^T`` and ``S = shrink(D - L, lambda_S)``:
    the Huber term is the closed-form minimum over S of
    ``0.5 ||U V^T + S - D||^2 + lambda_S ||S||_1``, so this is LAGO's objective
    restricted to rank k. Minimised by L-BFGS with backtracking
    (:func:`~dgmod_ros.core.baselines.lbfgs.lbfgs`) from a seeded random start
    (fastRPCA's start is unseeded randn).

    Parameters
    ----------
    rank : int, default=10
        Columns k of the factors (fastRPCA's default).
    lambda_l : float, default=0.451
        As :class:`~dgmod_ros.core.baselines.lago.LAGO`.
    lambda_s : float or None, default=None
        As LAGO: None is ``lambda_l / sqrt(max(n, m))``.
    max_iter : int, default=100
        L-BFGS iterations. fastRPCA's demo runs 500; 100 end within 0.1% of
        the converged objective at a quarter of the time (``docs/evaluation.md``).
        A warm start (``init``, the previous window's factors) stops earlier on
        the progress test.
    tol : float, default=1e-10
        L-BFGS gradient and progress tolerance (fastRPCA's demo ``optTol``,
        ``progTol``).
    memory : int, default=5
        L-BFGS memory; fastRPCA's demo uses 1, which ends higher after 100
        iterations (``docs/evaluation.md``).
    random_state : int, default=0
        Seed of the start.

    References
    ----------
    .. [1] C. Driggs, S. Becker, A. Aravkin, "Adapting Regularized Low-Rank
       Models for Parallel Architectures", SIAM J. Sci. Comput. 41(1), 2019.

    """

    def __init__(self, rank=10, lambda_l=0.451, lambda_s=None, max_iter=100, tol=1e-10,
                 memory=5, random_state=0):
        self.rank = rank
        self.lambda_l = lambda_l
        self.lambda_s = lambda_s
        self.max_iter = max_iter
        self.tol = tol
        self.memory = memory
        self.random_state = random_state

    def fit(self, data, frame_shape, init=None):
        """Separate one window (n pixels x m frames), from ``init`` factors if given."""
        data = check_window_data(data, frame_shape).astype(np.float64)
        n, m = data.shape
        k = int(min(self.rank, n, m))
        if k < 1:
            raise ValueError(f'rank must be a positive integer, got {self.rank!r}')
        lambda_s = (self.lambda_s if self.lambda_s is not None
                    else self.lambda_l / np.sqrt(max(n, m)))
        lambda_l = self.lambda_l
        rng = np.random.default_rng(self.random_state)
        if init is not None and init.left.shape == (n, k) and init.right.shape == (m, k):
            start = np.concatenate([init.left.ravel(), init.right.ravel()])
        else:
            start = rng.standard_normal((n + m) * k) * np.sqrt(np.abs(data).mean() / k)

        def objective(x):
            # With r = D - U V^T and c = clip(r, -lambda_S, lambda_S): the inner
            # minimiser S is r - c, so U V^T + S - D = -c and the Huber sum is
            # 0.5 ||c||^2 + lambda_S (||r||_1 - ||c||_1).
            left, right = x[:n * k].reshape(n, k), x[n * k:].reshape(m, k)
            residual = data - left @ right.T
            clipped = np.clip(residual, -lambda_s, lambda_s)
            value = (0.5 * lambda_l * (np.vdot(left, left) + np.vdot(right, right))
                     + 0.5 * np.vdot(clipped, clipped)
                     + lambda_s * (np.abs(residual).sum() - np.abs(clipped).sum()))
            grad = np.concatenate([(lambda_l * left - clipped @ right).ravel(),
                                   (lambda_l * right - clipped.T @ left).ravel()])
            return value, grad

        solution, value, self.n_iter_, converged = lbfgs(
            objective, start, memory=self.memory, max_iter=self.max_iter, grad_tol=self.tol,
            prog_tol=self.tol)
        left, right = solution[:n * k].reshape(n, k), solution[n * k:].reshape(m, k)
        low_rank = left @ right.T
        self.background_ = low_rank.astype(np.float32)
        self.foreground_ = shrink(data - low_rank, lambda_s).astype(np.float32)
        self.info_ = 0 if converged else self.n_iter_
        self.objective_ = float(value)
        self.lambda_s_ = lambda_s
        self.state_ = FactorState(left, right)
        return self
