# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The per-frame path's compiled kernels give their numpy references' results bit for bit."""

import cv2
from dgmod_ros.core.preprocess import frame_columns, to_float_channels
from dgmod_ros.core.streaming.blobs import BlobMotion, moving_share_reference
from dgmod_ros.core.streaming.coherence import mean_field_mask, mean_field_mask_reference
from dgmod_ros.core.streaming.ghost import _edge_strength, ghost_blobs, ghost_labels
from dgmod_ros.core.streaming.held_foreground import still_blob_pixels
from dgmod_ros.core.streaming.kernels import coherence as mean_field_kernel
from dgmod_ros.core.streaming.kernels import photometric as lighting_kernel
from dgmod_ros.core.streaming.kernels import warmup_background as warmup_kernel
from dgmod_ros.core.streaming.kernels.photometric import distortion, explained_pixels
from dgmod_ros.core.streaming.noise_levels import observed_median, warmup_noise
from dgmod_ros.core.streaming.photometric import LightingTest
from dgmod_ros.core.streaming.upsizing import to_input_size
import numpy as np
import pytest


def _field_case(rng, rows, cols, scalar_noise, nan=False):
    """Return distances and noise levels of a frame with blobs, noise, maybe non-finite pixels."""
    noise = (float(rng.uniform(0.002, 0.05)) if scalar_noise
             else rng.uniform(0.005, 0.05, rows * cols).astype(np.float32))
    z = np.abs(rng.normal(0, 2.5, (rows, cols))).astype(np.float32)
    for _ in range(3):                                  # people: regions far over k
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        z[r:r + rng.integers(1, 12), c:c + rng.integers(1, 12)] += rng.uniform(3, 15)
    distance = (z.ravel() * noise).astype(np.float32)
    if nan:
        distance[rng.integers(0, distance.size, 2)] = np.nan
    return distance, noise


@pytest.mark.parametrize('seed', range(12))
def test_mean_field_kernel_gives_the_reference_masks(seed):
    rng = np.random.default_rng(seed)
    rows, cols = int(rng.integers(1, 70)), int(rng.integers(1, 90))
    nan = seed % 4 == 1             # the kernel hands these to the reference
    distance, noise = _field_case(rng, rows, cols, scalar_noise=seed % 3 == 0, nan=nan)
    k, beta = float(rng.choice([6.0, 4.5, 3.0])), float(rng.choice([2.0, 0.7, 1.3, 0.0]))
    if seed % 2 == 0:               # each pixel its own k, as the moving-texture rule gives
        k = np.where(rng.random(rows * cols) < 0.3, np.float32(k / 2), np.float32(k))
    for sweeps, radius in ((5, 2), (2, 1), (3, 3)):
        spins = mean_field_kernel.mean_field_spins(distance, noise, k, beta, rows, cols, sweeps,
                                                   radius, 3.0, 50.0)
        assert (spins is None) == nan
        got = mean_field_mask(distance, noise, k, beta, (rows, cols, 3), sweeps, radius)
        expected = mean_field_mask_reference(distance, noise, k, beta, (rows, cols, 3),
                                             sweeps, radius)
        assert got.dtype == np.uint8 and got.shape == (rows, cols)
        assert np.array_equal(got, expected)


def test_mean_field_kernel_hands_numpy_float64_scalars_to_the_reference():
    # numpy computes in float64 with a numpy float64 beta: the kernel does not reproduce that.
    distance = np.ones(12, np.float32)
    assert mean_field_kernel.mean_field_spins(distance, 0.1, 6.0, np.float64(2.0), 3, 4, 5, 2,
                                              3.0, 50.0) is None
    assert mean_field_kernel.mean_field_spins(distance, 0.1, np.ones(5), 2.0, 3, 4, 5, 2,
                                              3.0, 50.0) is None
    assert mean_field_kernel.mean_field_spins(distance, np.ones(12), 6.0, 2.0, 3, 4, 5, 2,
                                              3.0, 50.0) is None


def test_numpy_tanh_is_exactly_one_beyond_the_saturation_bound():
    # The kernel writes +-1 without calling tanh beyond SATURATED: numpy's float32 tanh must agree.
    beyond = np.linspace(mean_field_kernel.SATURATED, 60.0, 2_000_001, dtype=np.float32)
    assert np.all(np.tanh(beyond) == 1.0)
    assert np.all(np.tanh(-beyond) == -1.0)


def test_a_tiny_or_nan_spin_sends_the_field_to_the_reference():
    spin = np.ones((2, 2), np.float32)
    index = np.array([0, 3], np.int64)
    assert mean_field_kernel._scatter(index, np.array([0.5, 0.0], np.float32), 2, spin)
    assert not mean_field_kernel._scatter(index, np.array([0.5, 1e-9], np.float32), 2, spin)
    assert not mean_field_kernel._scatter(index, np.array([np.nan, 1.0], np.float32), 2, spin)


def _blob_case(seed, rows=60, cols=80):
    """Return a mask of blobs, a frame, an earlier frame (some blobs still) and noise levels."""
    rng = np.random.default_rng(seed)
    n = rows * cols
    earlier = rng.uniform(0.2, 0.8, (3, n)).astype(np.float32)
    noise = rng.uniform(0.004, 0.02, n).astype(np.float32)
    frame = earlier + rng.normal(0, 0.004, (3, n)).astype(np.float32)
    background = rng.uniform(0.2, 0.8, (3, n)).astype(np.float32)
    mask = np.zeros((rows, cols), np.uint8)
    image = frame.reshape(3, rows, cols)
    for blob in range(6):
        r, c = rng.integers(0, rows - 8), rng.integers(0, cols - 8)
        h, w = rng.integers(2, 9), rng.integers(2, 9)
        mask[r:r + h, c:c + w] = 255
        if blob % 2:                                    # a moving blob
            image[:, r:r + h, c:c + w] += rng.uniform(0, 0.3, (3, h, w)).astype(np.float32)
        elif blob % 3 == 0:                             # a still blob with an edge in the frame
            image[:, r:r + h, c:c + w] = 0.9
    frame[0, rng.integers(0, n, 3)] = np.nan
    return mask, frame, background, earlier, noise


def _ghost_blobs_reference(mask, frame, background, earlier, noise, k):
    """Return the ghost test as numpy on the whole frame (before the shared labelling)."""
    rows, cols = mask.shape
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    moving_share = moving_share_reference(labels, count, frame, earlier, noise, k)
    border = cv2.morphologyEx(mask, cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
    owner = cv2.dilate(labels.astype(np.float32), np.ones((3, 3), np.uint8))
    owner = owner.astype(np.int32)[border]
    frame_edges = _edge_strength(frame.mean(axis=0).reshape(rows, cols))[border]
    background_edges = _edge_strength(background.mean(axis=0).reshape(rows, cols))[border]
    in_frame = np.bincount(owner, frame_edges, minlength=count)
    in_background = np.bincount(owner, background_edges, minlength=count)
    ghost = (moving_share < 0.1) & (in_background > in_frame)
    ghost[0] = False
    return ghost[labels]


@pytest.mark.parametrize('seed', range(8))
def test_blob_motion_counts_give_the_reference_shares(seed):
    mask, frame, _, earlier, noise = _blob_case(seed)
    blobs = BlobMotion(mask, frame, earlier, noise)
    for k in (6.0, 3.0, 0.5):
        expected = moving_share_reference(blobs.labels, blobs.count, frame, earlier, noise, k)
        assert np.array_equal(blobs.moving_share(k)[1:], expected[1:])


@pytest.mark.parametrize('seed', range(8))
def test_ghost_test_in_the_blobs_box_gives_the_whole_frame_reference(seed):
    mask, frame, background, earlier, noise = _blob_case(seed)
    # The background's edges against the frame's: some still blobs are ghosts, some not.
    for back in (background, frame[::-1].copy(), earlier):
        expected = _ghost_blobs_reference(mask, frame, back, earlier, noise, 6.0)
        assert np.array_equal(ghost_blobs(mask, frame, back, earlier, noise, 6.0), expected)


@pytest.mark.parametrize('seed', range(8))
def test_still_test_on_shared_labels_equals_labelling_the_mask_left_by_the_ghost_test(seed):
    mask, frame, background, earlier, noise = _blob_case(seed)
    blobs = BlobMotion(mask, frame, earlier, noise)
    shared = mask.copy()
    blobs.drop(ghost_labels(blobs, shared, frame, background, 6.0), shared)
    separate = mask.copy()
    separate[ghost_blobs(separate, frame, background, earlier, noise, 6.0)] = 0
    assert np.array_equal(shared, separate)
    for share in (0.0, 0.01, 0.3):
        assert np.array_equal(
            still_blob_pixels(shared, frame, earlier, noise, 3.0, share, blobs),
            still_blob_pixels(separate, frame, earlier, noise, 3.0, share))


@pytest.mark.parametrize('rows, cols', [(1, 1), (1, 7), (5, 3), (120, 160), (241, 319)])
def test_doubling_a_mask_is_the_thresholded_bilinear_interpolation(rows, cols):
    mask = np.where(np.random.default_rng(rows * cols).random((rows, cols)) < 0.4,
                    np.uint8(255), np.uint8(0))
    smooth = cv2.resize(mask, (2 * cols, 2 * rows), interpolation=cv2.INTER_LINEAR)
    expected = np.where(smooth > 127, np.uint8(255), np.uint8(0))
    assert np.array_equal(to_input_size(mask, (2 * rows, 2 * cols)), expected)


@pytest.mark.parametrize('seed', range(10))
def test_lighting_kernel_gives_the_reference_answers(seed):
    rng = np.random.default_rng(seed)
    rows, cols = int(rng.integers(1, 40)), int(rng.integers(1, 50))
    n = rows * cols
    background = rng.uniform(0, 1, (3, n)).astype(np.float32)
    background[:, :3] = 0                               # black: no chromaticity
    # Shadows, reflections (scaled background), other colours, and brightness ratios
    # at the cue's bound.
    gain = rng.choice([0.6, 0.635, 0.8, 1.0, 1.2, 1.365, 2.0], n).astype(np.float32)
    frame = gain * background + rng.normal(0, 0.02, (3, n)).astype(np.float32)
    frame[:, rng.random(n) < 0.3] = rng.uniform(0, 1, (3, 1)).astype(np.float32)
    frame[1, 5 % n] = np.nan
    noise = (rng.uniform(0.002, 0.03, n).astype(np.float32) if seed % 2
             else float(rng.uniform(0.002, 0.03)))
    chroma_level = rng.uniform(0.001, 0.02, n).astype(np.float32) if seed % 3 else None
    candidates = rng.random(n) < 0.7
    for cues in ((True, True), (True, False), (False, True)):
        test = LightingTest(*cues, texture_bits=int(rng.integers(0, 12)))
        args = (frame, background, noise, 6.0, (rows, cols, 3), candidates, chroma_level)
        assert np.array_equal(test.explains(*args), test.explains_reference(*args))
        assert explained_pixels(*args, *cues, test.texture_bits) is not None


@pytest.mark.parametrize('dtype', [np.uint8, np.uint16, np.float32, np.float64])
@pytest.mark.parametrize('channels', [3, 4])
def test_bgr_frames_give_the_columns_of_their_channels_reversed(dtype, channels):
    # OpenCV swaps the channels of the swappable types; the reference is the reversed view.
    rng = np.random.default_rng(channels)
    image = (rng.random((31, 45, channels)) * (255 if dtype == np.uint8 else 1.0)).astype(dtype)
    reference = np.ascontiguousarray(image[:, :, 2::-1])
    for scale in (0.5, 1.0, 0.4):
        got, shape = frame_columns(image, scale, 'rgb', 'bgr')
        expected, expected_shape = frame_columns(reference, scale, 'rgb', 'rgb')
        assert shape == expected_shape and np.array_equal(got, expected)


@pytest.mark.parametrize('dtype', [np.uint8, np.uint16])
@pytest.mark.parametrize('channels, order', [(3, 'rgb'), (3, 'bgr'), (4, 'bgr'), (4, 'rgb')])
def test_half_size_colour_columns_are_the_general_conversion_bit_for_bit(dtype, channels, order):
    # frame_columns takes one compiled pass for an 8- or 16-bit colour frame
    # at scale 0.5; the general path (float frame, OpenCV's area resize,
    # columns) is the reference, value_range clipping included, and a padded
    # image (rows a strided view, as a message with row padding gives) too.
    rng = np.random.default_rng(channels + len(order))
    top = np.iinfo(dtype).max
    padded = rng.integers(0, top, (48, 70, channels), endpoint=True, dtype=dtype)
    padded[0, :4] = top                                 # full scale: exactly 1.0
    cases = ((padded[:, :64], None), (np.ascontiguousarray(padded[:, :64]), 1000.0))
    for image, value_range in cases:
        got, shape = frame_columns(image, 0.5, 'rgb', order, value_range)
        channels_first = to_float_channels(image, order, 'rgb', value_range)
        small = cv2.resize(channels_first, (32, 24), interpolation=cv2.INTER_AREA)
        assert shape == (24, 32, 3)
        assert np.array_equal(got, small.reshape(-1, 3).T)
        assert got.dtype == np.float32 and got.flags.c_contiguous


@pytest.mark.parametrize('seed', range(4))
def test_window_chroma_kernel_gives_numpy_distortion(seed):
    rng = np.random.default_rng(seed)
    data = rng.random((3, 500, 7), dtype=np.float32)
    data[:, :20] *= np.float32(1e-4)                    # dark pixels: the energy floor
    residual = rng.normal(0, 0.05, data.shape).astype(np.float32)
    _, expected = distortion(data, data - residual)
    assert np.array_equal(lighting_kernel.window_chroma(data, residual), expected)
    assert lighting_kernel.window_chroma(data.astype(np.float64), residual) is None


@pytest.mark.parametrize('columns', [29, 30])
@pytest.mark.parametrize('order', ['C', 'F'])
def test_median_of_fully_observed_rows_is_numpys(columns, order):
    magnitude = np.abs(np.random.default_rng(columns).normal(0, 0.02, (400, columns)))
    magnitude = magnitude.astype(np.float32, order=order)   # F: the carry's residual
    median, count = observed_median(magnitude)
    assert median.dtype == np.float32 and np.array_equal(median, np.median(magnitude, axis=1))
    assert np.all(count == columns)


@pytest.mark.parametrize('columns', [1, 5, 30])
def test_median_of_observed_entries_is_the_lower_median_of_numpys_filled_sort(columns):
    rng = np.random.default_rng(columns)
    magnitude = rng.random((300, columns), dtype=np.float32)
    observed = rng.random((300, columns)) < 0.7
    observed[:3] = False                                  # rows with no entry observed
    median, count = observed_median(magnitude, observed)
    ordered = np.sort(np.where(observed, magnitude, np.inf), axis=1)
    expected_count = np.count_nonzero(observed, axis=1)
    assert np.array_equal(count, expected_count)
    assert np.array_equal(median, ordered[np.arange(300), np.maximum(expected_count - 1, 0) // 2])


@pytest.mark.parametrize('count', [1, 2, 3, 4, 5, 8, warmup_kernel.NETWORK_FRAMES + 1])
@pytest.mark.parametrize('channels', [1, 3])
def test_warmup_kernels_give_numpys_medians_and_differences(count, channels):
    rng = np.random.default_rng(count * 10 + channels)
    # Quantised values (ties, as 8-bit frames give) and a NaN in some entries.
    frames = [(rng.integers(0, 6, (channels, 300)) / 5).astype(np.float32)
              for _ in range(count)]
    frames[-1][0, 7] = np.nan
    frames[0][channels - 1, 11] = np.nan
    stack = np.stack(frames, axis=2)
    np.testing.assert_array_equal(warmup_kernel.entry_medians(frames),
                                  np.median(stack, axis=2))
    differences = warmup_kernel.difference_magnitudes(frames)
    assert differences.shape == (count - 1, 300)
    np.testing.assert_array_equal(differences, np.abs(np.diff(stack, axis=-1)).max(axis=0).T)


def test_warmup_noise_is_a_python_float_that_the_compiled_field_takes():
    rng = np.random.default_rng(1)
    frames = [rng.uniform(0, 1, (3, 64)).astype(np.float32) for _ in range(3)]
    level = warmup_noise(frames)
    assert type(level) is float
    distance = rng.uniform(0, 0.3, 64).astype(np.float32)
    assert mean_field_kernel.mean_field_spins(distance, level, 6.0, 2.0, 8, 8, 5, 2, 3.0,
                                              50.0) is not None
