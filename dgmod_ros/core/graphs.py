# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Spatial and temporal graph Laplacians of a window of frames (paper Sec. III-A).

Both graphs use Gaussian weights ``exp(-dist^2 / h^2)`` and the symmetric
normalised Laplacian ``Phi = I - W^-1/2 A W^-1/2``. When the filtering
parameter ``h`` is not given it defaults to a data-driven scale: ``h^2`` is
the median of the squared distances over the graph's edges, so a typical
edge gets weight ``exp(-1)`` whatever the video's contrast or window length.
"""

import cv2
import numpy as np
from scipy import ndimage
import scipy.sparse as sp

from .linalg import frames_major, gram_matrix


def normalized_laplacian(adjacency):
    """
    Return ``I - W^-1/2 A W^-1/2`` (dense, float64) for a dense symmetric adjacency ``A``.

    Isolated vertices (degree 0) get a zero row: they carry no smoothing.
    The m x m matrix of a window's frames is small: scipy.sparse's
    per-operation overhead had cost a hundred times its arithmetic.
    """
    adjacency = np.asarray(adjacency, dtype=np.float64)
    degree = adjacency.sum(axis=1)
    inv_sqrt = np.zeros_like(degree)
    np.divide(1.0, np.sqrt(degree), out=inv_sqrt, where=degree > 0)
    scaled = (inv_sqrt[:, None] * adjacency) * inv_sqrt[None, :]
    return np.diag((degree > 0).astype(np.float64)) - scaled


def _gaussian_weights(sq_dist, h):
    if h is None:
        positive = sq_dist[sq_dist > 0]
        h2 = float(np.median(positive)) if positive.size else 1.0
    else:
        h2 = float(h) ** 2
    return np.exp(-sq_dist / h2), np.sqrt(h2)


def temporal_laplacian(data, neighbors=4, h=None, gram=None):
    """
    Laplacian ``Phi_t`` (m x m) of the graph over the frames of a window.

    Parameters
    ----------
    data : ndarray (n, m)
        One column per frame.
    neighbors : int, default=4
        Each frame is joined to the ``neighbors`` frames nearest in time
        (``neighbors // 2`` on each side), as in the paper.
    h : float or None, default=None
        Temporal filtering parameter ``h_t``; None picks the median edge
        distance (see module docstring).
    gram : ndarray (m, m) or None
        ``(data.T @ data)`` in float64 where the caller has it already (the
        solver shares it with the weights' scale); None computes it.

    Returns
    -------
    laplacian : ndarray (m, m), float64
    h : float, the filtering parameter used.

    """
    m = data.shape[1]
    if gram is None:
        gram = gram_matrix(data)
    sq_norm = np.diag(gram)
    reach = max(1, neighbors // 2)
    rows, cols = [], []
    for offset in range(1, min(reach, m - 1) + 1):
        rows.append(np.arange(m - offset))
        cols.append(np.arange(offset, m))
    if not rows:
        return np.zeros((m, m)), 1.0 if h is None else float(h)
    rows = np.concatenate(rows)
    cols = np.concatenate(cols)
    sq_dist = np.clip(sq_norm[rows] + sq_norm[cols] - 2.0 * gram[rows, cols], 0.0, None)
    weights, h_used = _gaussian_weights(sq_dist, h)
    adjacency = np.zeros((m, m))
    adjacency[rows, cols] = weights
    adjacency[cols, rows] = weights
    return normalized_laplacian(adjacency), h_used


def _box_sum(image, patch_size):
    return cv2.boxFilter(image, -1, (patch_size, patch_size), normalize=False,
                         borderType=cv2.BORDER_REFLECT)


def spatial_laplacian_bands(data, frame_shape, patch_size=3, h=None, smoothing_sigma=0.0):
    """
    Diagonal bands of the Laplacian ``Phi_s`` of the 4-neighbour pixel graph.

    The weight of the edge between pixels i and j is
    ``exp(-||P_i - P_j||_F^2 / h_s^2)`` where ``P_i`` is the ``p x p`` patch
    around pixel i across all frames of the window. The squared patch distance
    of every horizontal (vertical) neighbour pair is a ``p x p`` box sum of the
    per-pixel squared differences summed over frames, so no loop over pixels
    is needed. In row-major pixel order the graph's Laplacian has the bands
    0, +-1 and +-n2, computed here from the edge weights directly: the fused
    solver applies the bands, and a sparse matrix of n x n with its index
    arrays cost more than the weights themselves (``docs/solver.md``,
    "Streaming").

    Parameters
    ----------
    data : ndarray (n, m)
        Frames as columns, pixels in row-major order.
    frame_shape : tuple (n1, n2)
        Rows and columns of a frame.
    patch_size : int, default=3
        Odd patch side ``p``.
    h : float or None, default=None
        Spatial filtering parameter ``h_s``; None picks the median edge distance.
    smoothing_sigma : float, default=0.0
        Standard deviation (pixels) of a Gaussian pre-smoothing of every frame
        before patch distances are taken; 0 disables it. Use for noisy video.

    Returns
    -------
    offsets : ndarray (k,) int64
        Ascending band offsets.
    bands : ndarray (k, n) float32
        ``Phi_s[i, i + offsets[k]] == bands[k, i]``, zero where ``i + offset``
        leaves the matrix or no edge joins the two pixels.
    h : float
        The filtering parameter used.

    """
    n1, n2 = frame_shape
    m = data.shape[1]
    n = n1 * n2
    # Frames-major (m, n1, n2): free for the fused solver's window, whose
    # memory is already in that order (linalg.frames_major).
    frames = frames_major(data).reshape(m, n1, n2)
    if smoothing_sigma > 0:
        frames = ndimage.gaussian_filter(frames, sigma=(0, smoothing_sigma, smoothing_sigma),
                                         mode='reflect')
    # (axis, offset in row-major order) of the right and the lower neighbour.
    directions = [(axis, step) for axis, step in ((1, 1), (0, n2)) if (n1, n2)[axis] >= 2]
    if not directions:
        return (np.zeros(1, dtype=np.int64), np.zeros((1, n), dtype=np.float32),
                1.0 if h is None else float(h))
    from .kernels.graphs import neighbour_square_sums     # numba: imported on first use
    sums = dict(zip((1, 0), neighbour_square_sums(frames)))
    dists = [_box_sum(sums[axis], patch_size) for axis, _ in directions]
    weights, h_used = _gaussian_weights(
        np.concatenate([d.ravel() for d in dists]).astype(np.float64), h)
    weights = weights.astype(np.float32)
    # Edge weight images: forward[axis][r, c] joins (r, c) to its next pixel
    # along axis (zero at the last row or column).
    forward = {}
    start = 0
    for (axis, _), dist in zip(directions, dists):
        image = np.zeros((n1, n2), dtype=np.float32)
        image[:n1 - (axis == 0), :n2 - (axis == 1)] = (
            weights[start:start + dist.size].reshape(dist.shape))
        forward[axis] = image
        start += dist.size
    # Each pixel's degree, summed in the order of the sparse row sum of
    # before (right, down, left, up): the same float32 sums.
    zero = np.zeros((n1, n2), dtype=np.float32)
    lower, right = forward.get(0, zero), forward.get(1, zero)
    degree = right + lower
    degree += np.roll(right, 1, axis=1)
    degree += np.roll(lower, 1, axis=0)
    inv_sqrt = np.zeros_like(degree)
    np.divide(1.0, np.sqrt(degree), out=inv_sqrt, where=degree > 0)
    bands = {0: (degree > 0).astype(np.float32).ravel()}
    for axis, step in directions:
        # Phi_s[i, j] = -(w_ij / sqrt(d_i)) / sqrt(d_j) for the edge to the next
        # pixel (j = i + step) and to the previous one (j = i - step), each
        # product in the sparse product's order: bit for bit the same matrix.
        for shift in (-1, 1):
            weight = forward[axis] if shift == -1 else np.roll(forward[axis], 1, axis=axis)
            coupling = -((inv_sqrt * weight) * np.roll(inv_sqrt, shift, axis=axis))
            bands[-shift * step] = coupling.ravel()
    offsets = np.array(sorted(bands), dtype=np.int64)
    return offsets, np.stack([bands[o] for o in offsets]), h_used


def diagonal_bands(matrix):
    """
    Return ``(offsets, bands)`` with ``matrix[i, i + offsets[k]] == bands[k, i]``.

    ``matrix`` is square (scipy sparse or dense); ``bands`` is float32 of shape
    ``(len(offsets), n)``, zero where ``i + offset`` leaves the matrix. The
    graph Laplacians are banded (4-neighbour pixels in row-major order:
    offsets 0, +-1, +-n2; frames: the temporal reach), so a product with them
    is a few shifted multiply-adds per row that the compiler vectorises.
    """
    if sp.issparse(matrix):
        coo = sp.coo_matrix(matrix)
        coo.sum_duplicates()
        rows, cols, values = coo.row, coo.col, coo.data
    else:
        rows, cols = np.nonzero(matrix)
        values = matrix[rows, cols]
    n = matrix.shape[0]
    diff = cols.astype(np.int64) - rows.astype(np.int64)
    offsets = np.unique(diff)
    bands = np.zeros((offsets.size, n), dtype=np.float32)
    bands[np.searchsorted(offsets, diff), rows] = values
    return offsets.astype(np.int64), bands


def banded_matrix(offsets, bands):
    """Return the sparse CSR matrix with ``matrix[i, i + offsets[k]] == bands[k, i]``."""
    n = bands.shape[1]
    rows, cols, values = [], [], []
    for offset, band in zip(offsets, bands):
        row = np.arange(max(0, -offset), min(n, n - offset))
        row = row[band[row] != 0]
        rows.append(row)
        cols.append(row + offset)
        values.append(band[row])
    return sp.csr_matrix((np.concatenate(values), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, n), dtype=bands.dtype)


def spatial_laplacian(data, frame_shape, patch_size=3, h=None, smoothing_sigma=0.0):
    """
    Laplacian ``Phi_s`` (n x n, sparse) of the 4-neighbour pixel graph.

    The matrix of :func:`spatial_laplacian_bands` (same parameters).

    Returns
    -------
    laplacian : scipy.sparse.csr_matrix (n, n), float32
    h : float, the filtering parameter used.

    """
    offsets, bands, h_used = spatial_laplacian_bands(data, frame_shape, patch_size, h,
                                                     smoothing_sigma)
    return banded_matrix(offsets, bands), h_used
