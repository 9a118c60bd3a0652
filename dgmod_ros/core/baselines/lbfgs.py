# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""A plain limited-memory BFGS with Armijo backtracking, as fastRPCA's split SPCP uses."""

from collections import deque

import numpy as np


def lbfgs(objective, start, memory=5, max_iter=100, grad_tol=1e-10, prog_tol=1e-10):
    """
    Minimise a smooth ``objective(x) -> (value, gradient)`` from ``start``.

    Two-loop recursion with ``memory`` pairs; the first step has length
    ``min(1, 1/||g||_1)`` and later ones 1, backtracked (halved) until the
    Armijo condition (c1 = 1e-4) holds, as minFunc does. Stops when
    ``max |g| <= grad_tol``, when the value changes by less than ``prog_tol``
    relative, or after ``max_iter`` iterations. scipy's L-BFGS-B spent more time
    in its bound-constrained bookkeeping than this whole update takes
    (``docs/evaluation.md``).

    Returns
    -------
    x : ndarray
    value : float
    iterations : int
    converged : bool

    """
    x = np.asarray(start, dtype=np.float64).copy()
    value, grad = objective(x)
    pairs = deque(maxlen=memory)
    for iteration in range(1, max_iter + 1):
        if np.max(np.abs(grad)) <= grad_tol:
            return x, value, iteration - 1, True
        direction = -grad
        alphas = []
        for s, y, rho in reversed(pairs):
            alpha = rho * np.vdot(s, direction)
            direction -= alpha * y
            alphas.append(alpha)
        if pairs:
            s, y, _ = pairs[-1]
            direction *= np.vdot(s, y) / np.vdot(y, y)
        for (s, y, rho), alpha in zip(pairs, reversed(alphas)):
            direction += (alpha - rho * np.vdot(y, direction)) * s
        slope = np.vdot(grad, direction)
        if slope >= 0:                      # not a descent direction: restart
            pairs.clear()
            direction, slope = -grad, -np.vdot(grad, grad)
        step = min(1.0, 1.0 / np.abs(grad).sum()) if iteration == 1 else 1.0
        for _ in range(30):
            candidate = x + step * direction
            new_value, new_grad = objective(candidate)
            if new_value <= value + 1e-4 * step * slope:
                break
            step *= 0.5
        else:
            return x, value, iteration, False
        s, y = candidate - x, new_grad - grad
        curvature = np.vdot(s, y)
        if curvature > 1e-12:
            pairs.append((s, y, 1.0 / curvature))
        converged = abs(value - new_value) <= prog_tol * max(abs(value), 1.0)
        x, value, grad = candidate, new_value, new_grad
        if converged:
            return x, value, iteration, True
    return x, value, max_iter, False
