# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from dgmod_ros.core.graphs import (banded_matrix, diagonal_bands, normalized_laplacian,
                                   spatial_laplacian, spatial_laplacian_bands,
                                   temporal_laplacian)
from dgmod_ros.core.kernels.graphs import neighbour_square_sums, neighbour_square_sums_reference
from dgmod_ros.core.linalg import gram_matrix
import numpy as np
import pytest
import scipy.sparse as sp


@pytest.fixture
def window():
    rng = np.random.default_rng(3)
    frames = rng.random((12, 9, 7)).astype(np.float32)       # rows x cols x frames
    frames[:, :4] += 0.8                                       # an edge the weights must see
    return frames.reshape(-1, 7), (12, 9)


def _check_normalized_laplacian(laplacian, degree_vector):
    dense = (laplacian.toarray() if sp.issparse(laplacian) else laplacian).astype(np.float64)
    assert np.allclose(dense, dense.T, atol=1e-6)
    eigenvalues = np.linalg.eigvalsh(dense)
    assert eigenvalues.min() > -1e-5                           # positive semi-definite
    assert eigenvalues.max() < 2 + 1e-5                        # normalized: spectrum in [0, 2]
    # W^(1/2) 1 spans the null space of I - W^-1/2 A W^-1/2.
    null = np.sqrt(degree_vector)
    assert np.linalg.norm(dense @ null) < 1e-5 * np.linalg.norm(null)


def test_spatial_laplacian_properties(window):
    data, shape = window
    laplacian, h = spatial_laplacian(data, shape)
    assert sp.issparse(laplacian) and laplacian.dtype == np.float32
    assert laplacian.shape == (data.shape[0],) * 2
    assert h > 0
    adjacency = sp.eye(laplacian.shape[0]) - laplacian
    # 4-neighbour graph: at most 4 off-diagonal entries per row.
    off = adjacency.tocsr()
    off.setdiag(0)
    off.eliminate_zeros()
    assert np.diff(off.indptr).max() <= 4
    # Recover the degrees from the unnormalised weights to check the null space.
    degrees = _degrees_from_normalized(laplacian)
    _check_normalized_laplacian(laplacian, degrees)


def _degrees_from_normalized(laplacian):
    # The null vector of a connected normalized Laplacian is W^(1/2) 1; get it
    # as the eigenvector of the smallest eigenvalue, squared.
    values, vectors = np.linalg.eigh(laplacian.toarray().astype(np.float64))
    return vectors[:, 0] ** 2


def test_spatial_weights_follow_patch_similarity(window):
    data, shape = window
    laplacian, _ = spatial_laplacian(data, shape, patch_size=1, h=1.0)
    dense = -laplacian.toarray()
    cube = data.reshape(shape + (-1,))
    idx = np.arange(shape[0] * shape[1]).reshape(shape)
    # Same-side neighbours are more similar than neighbours across the edge,
    # so (after normalisation) their coupling is stronger.
    same = dense[idx[5, 1], idx[5, 2]]
    across = dense[idx[5, 3], idx[5, 4]]
    assert same > across
    # With p = 1 and h = 1 the raw weight is exp(-sum_t (x_i - x_j)^2).
    raw = np.exp(-np.sum((cube[5, 1] - cube[5, 2]) ** 2))
    assert raw > np.exp(-np.sum((cube[5, 3] - cube[5, 4]) ** 2))


def test_temporal_laplacian_properties(window):
    data, _ = window
    laplacian, h = temporal_laplacian(data, neighbors=4)
    dense = laplacian
    m = data.shape[1]
    assert dense.shape == (m, m) and h > 0
    # Only frames within two steps are joined.
    rows, cols = np.nonzero(dense)
    assert np.abs(rows - cols).max() <= 2
    values, vectors = np.linalg.eigh(dense)
    _check_normalized_laplacian(laplacian, vectors[:, 0] ** 2)


def test_temporal_laplacian_from_a_given_gram_is_the_same(window):
    # The solver computes D^T D once for Phi_t and the weights' scale.
    data, _ = window
    alone, h_alone = temporal_laplacian(data, neighbors=4)
    shared, h_shared = temporal_laplacian(data, neighbors=4, gram=gram_matrix(data))
    assert h_alone == h_shared
    assert np.array_equal(alone, shared)


def test_normalized_laplacian_is_the_sparse_product():
    # The dense m x m form replaced I - W^-1/2 A W^-1/2 in scipy.sparse. Its
    # degrees are summed in another order (an ulp in float64); the float32
    # matrix the solver applies is the same.
    rng = np.random.default_rng(5)
    m = 9
    adjacency = np.zeros((m, m))
    for offset in (1, 2):
        weights = rng.random(m - offset)
        adjacency[np.arange(m - offset), np.arange(offset, m)] = weights
        adjacency[np.arange(offset, m), np.arange(m - offset)] = weights
    adjacency[4, :] = adjacency[:, 4] = 0.0                    # an isolated frame
    sparse = sp.csr_matrix(adjacency)
    degree = np.asarray(sparse.sum(axis=1)).ravel()
    inv_sqrt = np.zeros_like(degree)
    np.divide(1.0, np.sqrt(degree), out=inv_sqrt, where=degree > 0)
    scale = sp.diags(inv_sqrt)
    expected = (sp.diags((degree > 0).astype(float)) - scale @ sparse @ scale).toarray()
    laplacian = normalized_laplacian(adjacency)
    assert np.allclose(laplacian, expected, rtol=0, atol=1e-15)
    assert np.array_equal(laplacian.astype(np.float32), expected.astype(np.float32))
    assert laplacian[4, 4] == 0.0 and not laplacian[4].any()


def test_default_filtering_parameter_is_median_edge_distance(window):
    data, _ = window
    gram = data.T.astype(np.float64) @ data
    d2 = [gram[i, i] + gram[j, j] - 2 * gram[i, j]
          for i in range(data.shape[1]) for j in range(i + 1, min(i + 3, data.shape[1]))]
    _, h = temporal_laplacian(data, neighbors=4)
    assert h == pytest.approx(np.sqrt(np.median(d2)), rel=1e-6)


def test_smoothing_changes_weights_but_not_structure(window):
    data, shape = window
    plain, _ = spatial_laplacian(data, shape)
    smooth, _ = spatial_laplacian(data, shape, smoothing_sigma=1.0)
    assert plain.nnz == smooth.nnz
    assert not np.allclose(plain.toarray(), smooth.toarray())


def _laplacian_from_definition(data, shape, patch_size):
    """Dense ``I - W^-1/2 A W^-1/2`` with patch distances summed pixel by pixel (small images)."""
    n1, n2 = shape
    cube = data.reshape(n1, n2, -1).astype(np.float64)
    half = patch_size // 2
    padded = np.pad(cube, ((half + 1, half + 1), (half + 1, half + 1), (0, 0)), mode='reflect')
    edges, dists = [], []
    for r in range(n1):
        for c in range(n2):
            for dr, dc in ((0, 1), (1, 0)):
                if r + dr >= n1 or c + dc >= n2:
                    continue
                rows = slice(r + 1, r + 1 + patch_size)
                cols = slice(c + 1, c + 1 + patch_size)
                here = padded[rows, cols]
                there = padded[r + dr + 1:r + dr + 1 + patch_size,
                               c + dc + 1:c + dc + 1 + patch_size]
                edges.append((r * n2 + c, (r + dr) * n2 + c + dc))
                dists.append(np.sum((here - there) ** 2))
    h2 = np.median(dists)
    adjacency = np.zeros((n1 * n2,) * 2)
    for (i, j), dist in zip(edges, dists):
        adjacency[i, j] = adjacency[j, i] = np.exp(-dist / h2)
    scale = 1 / np.sqrt(adjacency.sum(axis=1))
    return np.eye(n1 * n2) - scale[:, None] * adjacency * scale[None, :]


@pytest.mark.parametrize('shape', [(12, 9), (1, 9), (9, 1), (2, 2)])
def test_spatial_bands_are_the_laplacian_of_the_definition(shape):
    rng = np.random.default_rng(5)
    data = rng.random((shape[0] * shape[1], 6)).astype(np.float32)
    # Patch size 1: the definition's reflected border and the box filter's agree.
    offsets, bands, _ = spatial_laplacian_bands(data, shape, patch_size=1)
    expected = _laplacian_from_definition(data, shape, 1)
    assert np.allclose(banded_matrix(offsets, bands).toarray(), expected, atol=1e-6)
    assert np.array_equal(offsets, np.unique(offsets))
    n = shape[0] * shape[1]
    for offset, band in zip(offsets, bands):
        rows = np.arange(n)
        inside = (rows + offset >= 0) & (rows + offset < n)
        assert np.all(band[~inside] == 0)
        assert np.allclose(band[inside], expected[rows[inside], rows[inside] + offset],
                           atol=1e-6)


def test_diagonal_bands_reproduce_the_matrix():
    rng = np.random.default_rng(3)
    dense = np.where(rng.random((9, 9)) < 0.3, rng.standard_normal((9, 9)), 0.0)
    for matrix in (sp.csr_matrix(dense), dense):
        offsets, bands = diagonal_bands(matrix)
        rebuilt = np.zeros_like(dense)
        for k, offset in enumerate(offsets):
            for i in range(9):
                if 0 <= i + offset < 9:
                    rebuilt[i, i + offset] = bands[k, i]
        assert np.allclose(rebuilt, dense, atol=1e-6)


@pytest.mark.parametrize('shape', [(12, 9), (1, 9), (9, 1), (1, 1)])
def test_neighbour_square_sums_are_the_frame_sums_in_order(shape):
    rows, cols = shape
    frames = np.random.default_rng(7).random((11, rows, cols)).astype(np.float32)
    right, down = neighbour_square_sums(frames)
    assert right.shape == (rows, cols - 1) and down.shape == (rows - 1, cols)
    # float32 sums over the frames in their order, as the einsum of before adds them.
    expected_right, expected_down = neighbour_square_sums_reference(frames)
    assert np.array_equal(right, expected_right) and np.array_equal(down, expected_down)
    # The solver's frames-major window (an F-ordered n x m view) and a C-ordered
    # copy give the same Laplacian.
    window = frames.reshape(11, -1).T
    for a, b in zip(spatial_laplacian_bands(window, shape),
                    spatial_laplacian_bands(np.ascontiguousarray(window), shape)):
        assert np.array_equal(a, b)
