# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The observed entries of a window's residual, ready for their per-pixel median, in one pass.

:func:`~dgmod_ros.core.streaming.noise_levels.observed_median` sorts each
pixel's row with the unobserved entries set to infinity, so that they sort
last, and counts the observed ones. In numpy those are ``np.where`` and
``np.count_nonzero`` along the rows, two passes that together cost more
than the sort itself (docs/solver.md, "Where a converged sweep's time goes").
:func:`observed_rows` writes the filled rows and the counts in one pass,
with the same values. It is serial and ``nogil``; numba's process-wide
settings come with ``njit`` from :mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ...numba_setup import njit, register_pass


@njit(cache=True, nogil=True)
def _observed_rows(magnitude, observed, filled, count):
    infinity = np.float32(np.inf)
    for i in range(magnitude.shape[0]):
        seen = 0
        for j in range(magnitude.shape[1]):
            if observed[i, j]:
                filled[i, j] = magnitude[i, j]
                seen += 1
            else:
                filled[i, j] = infinity
        count[i] = seen


def observed_rows(magnitude, observed):
    """
    Return ``np.where(observed, magnitude, inf)`` (n, m) and each row's observed count (n,).

    ``magnitude`` is float32 and ``observed`` bool, both (n, m); the rows
    come back C-ordered, as the sort along them wants.
    """
    magnitude = np.ascontiguousarray(magnitude, dtype=np.float32)
    observed = np.ascontiguousarray(observed, dtype=np.bool_)
    filled = np.empty(magnitude.shape, dtype=np.float32)
    count = np.empty(magnitude.shape[0], dtype=np.int64)
    _observed_rows(magnitude, observed, filled, count)
    return filled, count


def observed_rows_reference(magnitude, observed):
    """Return :func:`observed_rows` computed in numpy."""
    filled = np.where(observed, np.asarray(magnitude, dtype=np.float32), np.float32(np.inf))
    return filled, np.count_nonzero(observed, axis=1).astype(np.int64)


def _examples():
    rng = np.random.default_rng(0)
    return [(rng.uniform(0, 1, (500, m)).astype(np.float32), rng.uniform(0, 1, (500, m)) < 0.7)
            for m in (1, 6, 30)]


register_pass(observed_rows, _examples, observed_rows_reference)
