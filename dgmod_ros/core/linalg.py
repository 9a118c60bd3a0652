# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Small dense linear-algebra kernels shared by every solver in the core."""

import numpy as np


def shrink(x, threshold, out=None):
    """
    Soft thresholding ``sign(x) * max(|x| - threshold, 0)``, elementwise.

    Written as ``x - clip(x, -t, t)``: two passes and no temporary for the
    sign, which matters on n x m arrays inside an ADMM loop.
    """
    clipped = np.clip(x, -threshold, threshold)
    if out is None:
        return x - clipped
    return np.subtract(x, clipped, out=out)


def thin_svd(matrix, rank=None):
    """
    Thin SVD of a tall ``n x m`` matrix through its ``m x m`` Gram matrix.

    Costs O(n m^2) instead of a general SVD of the tall matrix. Singular
    vectors of singular values below ``1e-6 * sigma_max`` are unreliable in
    this route (their accuracy is that of ``sigma^2``), so they are dropped:
    every caller thresholds such small values away anyway.

    Returns
    -------
    left : ndarray (n, k)
    sigma : ndarray (k,), descending
    right : ndarray (m, k)

    """
    gram = (matrix.T @ matrix).astype(np.float64)
    eigval, eigvec = np.linalg.eigh(gram)
    order = np.argsort(eigval)[::-1]
    eigval = np.clip(eigval[order], 0.0, None)
    eigvec = eigvec[:, order]
    sigma = np.sqrt(eigval)
    keep = sigma > 1e-6 * max(sigma[0], np.finfo(np.float64).tiny) if sigma.size else sigma > 0
    if rank is not None:
        keep[rank:] = False
    sigma = sigma[keep]
    right = eigvec[:, keep]
    left = (matrix @ (right / sigma).astype(matrix.dtype))
    return left, sigma.astype(matrix.dtype), right.astype(matrix.dtype)


def relative_change(new, old):
    """Return ``||new - old||_F / ||old||_F`` (an all-zero ``old`` gives inf, or 0 if equal)."""
    denom = np.linalg.norm(old)
    diff = np.linalg.norm(new - old)
    if denom == 0.0:
        return 0.0 if diff == 0.0 else np.inf
    return float(diff / denom)
