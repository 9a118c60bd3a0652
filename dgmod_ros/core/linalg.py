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


def drop_oldest(array, count, fill, axis=1):
    """
    Return ``array`` with its first ``count`` slices along ``axis`` dropped.

    The remaining slices move to the front and the last ``count`` are set to
    ``fill`` (broadcast): the warm start of a window that moved by ``count``
    frames. ``axis`` is the frame axis (1 for n x m matrices, 0 for m x k factors).
    """
    moved = np.empty_like(array)
    front = [slice(None)] * array.ndim
    back = [slice(None)] * array.ndim
    source = [slice(None)] * array.ndim
    front[axis] = slice(None, -count)
    source[axis] = slice(count, None)
    back[axis] = slice(-count, None)
    moved[tuple(front)] = array[tuple(source)]
    moved[tuple(back)] = fill
    return moved
