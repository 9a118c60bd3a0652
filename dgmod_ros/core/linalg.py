# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Small dense linear-algebra kernels shared by every solver in the core."""

import cv2
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


def gram_matrix(matrix):
    """
    Return ``matrix.T @ matrix`` in float64, from the product in the matrix's own type.

    A float32 matrix whose transpose is C-contiguous (the fused solver's
    frames-major windows and states) goes to the compiled
    :func:`~dgmod_ros.core.kernels.dgmod.frames_gram`, faster on one thread than
    BLAS here; anything else to BLAS.
    """
    rows = matrix.T
    if matrix.ndim == 2 and matrix.dtype == np.float32 and rows.flags.c_contiguous:
        from .kernels.dgmod import frames_gram      # numba: imported on first use
        return frames_gram(rows)
    return (matrix.T @ matrix).astype(np.float64)


def gram_eigh(matrix, vectors=True, gram=None):
    """
    Return the singular values (descending) and right singular vectors of a tall matrix.

    Through the eigendecomposition of the ``m x m`` Gram matrix in float64:
    O(n m^2) instead of a general SVD of the ``n x m`` matrix (``docs/solver.md``
    has the measured difference). Accurate for singular values above about
    ``1e-6 sigma_max``; every caller thresholds smaller ones away. With
    ``vectors=False`` only the singular values are computed (and returned).
    ``gram``: ``(matrix.T @ matrix)`` in float64 where the caller has it.
    """
    if gram is None:
        gram = gram_matrix(matrix)
    if not vectors:
        return np.sqrt(np.clip(np.linalg.eigvalsh(gram)[::-1], 0.0, None))
    eigval, eigvec = np.linalg.eigh(gram)
    return np.sqrt(np.clip(eigval[::-1], 0.0, None)), eigvec[:, ::-1]


def top_singular_value(matrix, gram=None):
    """Return the largest singular value of a tall matrix (``gram``: see :func:`gram_eigh`)."""
    return float(gram_eigh(matrix, vectors=False, gram=gram)[0])


def mixing_factors(gram, transform):
    """
    Factor the mixing matrix of :func:`singular_value_map` from the Gram matrix ``A^T A``.

    Returns ``(left, right_t, sigma, rank)`` with ``left = B_k diag(transform(sigma) / sigma)``
    (m x k) and ``right_t = B_k^T`` (k x m) over the k singular values that the
    transform keeps positive, so that ``A left right_t`` is the mapped matrix.
    A non-finite Gram matrix gives NaN singular values and rank 0 (callers
    check ``sigma`` to detect a diverged iterate).
    """
    gram = np.asarray(gram, dtype=np.float64)
    m = gram.shape[0]
    if not np.isfinite(gram).all():     # a diverged iterate: NaN singular values, no factors
        return np.zeros((m, 0)), np.zeros((0, m)), np.full(m, np.nan), 0
    eigval, eigvec = np.linalg.eigh(gram)
    sigma, right = np.sqrt(np.clip(eigval[::-1], 0.0, None)), eigvec[:, ::-1]
    new = np.asarray(transform(sigma), dtype=np.float64)
    keep = (new > 0) & (sigma > 1e-12 * max(sigma[0], 1e-300))
    return (right[:, keep] * (new[keep] / sigma[keep]), right[:, keep].T, sigma,
            int(np.count_nonzero(keep)))


def singular_value_map(matrix, transform):
    """
    Return ``A diag(transform(sigma)) B^T`` for the thin SVD ``A diag(sigma) B^T`` of ``matrix``.

    Only ``B`` is formed: the result is ``matrix B diag(transform(sigma) / sigma) B^T``.
    ``transform`` maps the descending singular values to new non-negative
    ones (a shrinkage or a projection).

    Returns
    -------
    result : ndarray, the shape and dtype of ``matrix``
    sigma : ndarray (m,), the singular values of ``matrix``
    rank : int, how many transformed values are positive

    """
    left, right_t, sigma, rank = mixing_factors(matrix.T @ matrix, transform)
    return matrix @ (left @ right_t).astype(matrix.dtype), sigma, rank


def thin_svd(matrix, rank=None, rtol=1e-6):
    """
    Return the thin SVD ``(left, sigma, right)`` of a tall matrix through :func:`gram_eigh`.

    Singular values below ``rtol * sigma_max`` are dropped, and all but the
    first ``rank`` when ``rank`` is given.
    """
    sigma, right = gram_eigh(matrix)
    keep = sigma > rtol * max(sigma[0], np.finfo(np.float64).tiny)
    if rank is not None:
        keep[rank:] = False
    sigma, right = sigma[keep], right[:, keep]
    left = matrix @ (right / sigma).astype(matrix.dtype)
    return left, sigma.astype(matrix.dtype), right.astype(matrix.dtype)


def c_order(matrix):
    """
    Return a 2-D float32 array in C order, by OpenCV's blocked transpose when it is F-ordered.

    The fused solver's iterates are F-ordered (``n x m`` views of frames-major
    arrays, :func:`frames_major`); numpy's strided
    transpose of such a tall matrix took ten times as long as a copy, and
    OpenCV's about twice (docs/solver.md).
    """
    matrix = np.asarray(matrix, dtype=np.float32)
    if matrix.flags.c_contiguous:
        return matrix
    if matrix.flags.f_contiguous:
        return cv2.transpose(matrix.T)
    return np.ascontiguousarray(matrix)


def frames_major(matrix):
    """
    Return the ``(m, n)`` C-contiguous transpose of a float32 window ``matrix`` (n, m).

    The layout of the fused solver's compiled pass
    (:func:`~dgmod_ros.core.kernels.dgmod.primal_pass`). No copy when
    ``matrix`` already is such a transpose (an F-ordered ``n x m`` array, as
    the fused solver's state is); else a blocked transpose (:func:`c_order`).
    """
    return c_order(np.asarray(matrix, dtype=np.float32).T)


def row_median(matrix):
    """
    Return numpy's median of each row (n,) of a float32 matrix (even rows: the middle two's mean).

    From a sort of a C-ordered copy: ``np.median`` along the rows of the
    fused solver's frames-major window (an F-ordered view, so each row is
    strided) took several times as long (docs/solver.md, "Where a converged
    sweep's time goes"). The entries must be finite (a window is checked on
    the way in), where the two agree.
    """
    ordered = np.sort(c_order(matrix), axis=1)
    half = ordered.shape[1] // 2
    if ordered.shape[1] % 2:
        return ordered[:, half]
    return (ordered[:, half - 1] + ordered[:, half]) / np.float32(2)


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
