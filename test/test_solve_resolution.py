# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The window solve at a capped size and the full-size background carried from it."""

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import cv2
from dgmod_ros import config
from dgmod_ros.core.dgmod import DualGraphMOD
from dgmod_ros.core.masks import MaskRule
from dgmod_ros.core.numba_setup import use_threads
from dgmod_ros.core.streaming.fast_path import background_basis
from dgmod_ros.core.streaming.kernels.solve_resolution import normal_equations
from dgmod_ros.core.streaming.noise_levels import pixel_noise
from dgmod_ros.core.streaming.photometric import chroma_noise
from dgmod_ros.core.streaming.results import WindowSnapshot
from dgmod_ros.core.streaming.solve_resolution import (carry_backgrounds, ColumnCache,
                                                       downsample_window,
                                                       PixelSample, resample_columns,
                                                       resample_frames, solve_shape, solve_spd,
                                                       take_pixels)
from dgmod_ros.core.streaming.window_solve import solve_window
from dgmod_ros.core.synthetic import synthetic_scene
import numba
import numpy as np
import pytest

FULL = (48, 64, 1)
HALF = (24, 32, 1)


def test_solve_shape_scales_then_caps_pixels_at_the_frames_aspect():
    assert solve_shape((480, 640, 3), 320 * 240, 0.5) == (240, 320, 3)
    assert solve_shape((240, 320, 3), 320 * 240, 0.5) == (120, 160, 3)
    assert solve_shape((256, 384, 3), 10**6, 0.5) == (128, 192, 3)
    assert solve_shape((480, 640, 3), 320 * 240) == (240, 320, 3)
    assert solve_shape((240, 320, 3), 320 * 240) == (240, 320, 3)      # at the cap: itself
    assert solve_shape((256, 384, 3), 320 * 240) == (226, 339, 3)
    rows, cols, _ = solve_shape((1080, 1920, 1), 320 * 240)
    assert rows * cols <= 320 * 240 and abs(cols / rows - 1920 / 1080) < 0.01


def test_resampling_more_columns_than_one_resize_takes():
    columns = np.random.default_rng(0).random((HALF[0] * HALF[1], 300), dtype=np.float32)
    up = resample_columns(columns, HALF, FULL, cv2.INTER_LINEAR)
    # Column 200 lies in the second group of 128: resized like any other.
    alone = cv2.resize(columns[:, 200].reshape(HALF[:2]), (FULL[1], FULL[0]),
                       interpolation=cv2.INTER_LINEAR)
    assert up.shape == (FULL[0] * FULL[1], 300)
    assert np.allclose(up[:, 200], alone.ravel())
    # Area averaging: all columns in one call at an integer ratio, 4 at a time otherwise.
    for small in (HALF, (20, 27, 1)):
        down = resample_columns(up, FULL, small, cv2.INTER_AREA)
        alone = cv2.resize(up[:, 200].reshape(FULL[:2]), (small[1], small[0]),
                           interpolation=cv2.INTER_AREA)
        assert down.shape == (small[0] * small[1], 300)
        assert np.allclose(down[:, 200], alone.ravel(), atol=1e-6)


def test_pixel_sample_picks_one_full_size_pixel_per_solved_one():
    sample = PixelSample((48, 64, 3), (24, 32, 3))
    # At half size, the lower right pixel of each 2 x 2 block of the area averaging.
    assert np.array_equal(sample.pixels[:3], [65, 67, 69])
    assert sample.pixels[-1] == 48 * 64 - 1
    odd = PixelSample((256, 384), (226, 339))      # CAVIAR's aspect, not an integer ratio
    assert odd.pixels.size == 226 * 339 == np.unique(odd.pixels).size
    assert odd.pixels.max() < 256 * 384


def test_noise_levels_read_at_the_sample_and_upsampled_match_every_pixels():
    rng = np.random.default_rng(5)
    shape, m = (48, 64, 3), 30
    level = np.tile(np.linspace(0.01, 0.04, shape[1], dtype=np.float32), (shape[0], 1))
    level[10:30, 8:24] = 0.08                          # a noisy patch (leaves, a screen)
    residual = (rng.normal(0.0, 1.0, (3, level.size, m)) * level.reshape(1, -1, 1)
                ).astype(np.float32)
    residual[:, :, :5] += np.float32(0.5) * (rng.random((1, level.size, 5)) < 0.2)  # movers
    data = (0.5 + rng.uniform(0.0, 0.2, (3, level.size, 1)) + residual).astype(np.float32)
    sample = PixelSample(shape, (24, 32, 3))
    pairs = (
        (pixel_noise(residual, shape),
         pixel_noise(sample.take(residual), shape, sample=sample)),
        (chroma_noise(data, residual, shape),
         chroma_noise(sample.take(data), sample.take(residual), shape, sample=sample)),
    )
    patch = np.zeros(shape[:2], np.uint8)
    patch[10:30, 8:24] = 1
    square = np.ones((3, 3), np.uint8)
    border = (cv2.dilate(patch, square) > cv2.erode(patch, square)).ravel()
    for every, sampled in pairs:
        assert sampled.shape == every.shape == (level.size,) and sampled.dtype == np.float32
        error = np.abs(sampled - every) / every
        # Measured: median 0.9% / 1.2%, 90th percentile 6.2% / 7.4%, largest
        # off the patch's border 20% / 18%.
        assert np.median(error) < 0.03
        assert np.percentile(error, 90) < 0.1
        assert error[~border].max() < 0.25
        # On it the coarser grid may put the edge one pixel off: each level
        # lies within those of its 3 x 3 neighbourhood, give or take the
        # sample's own error (measured 0.87 to 1.12 times their range).
        image = every.reshape(shape[:2])
        low, high = cv2.erode(image, square).ravel(), cv2.dilate(image, square).ravel()
        assert np.all(sampled >= 0.8 * low) and np.all(sampled <= 1.25 * high)


def test_frames_major_windows_resample_and_sample_as_pixel_major_ones():
    # The snapshot's window is frames-major in memory, a (C, n, m) view of
    # (m, C, n): the same values as the C-ordered window, read along rows.
    rng = np.random.default_rng(2)
    frames = rng.random((30, 3, FULL[0] * FULL[1]), dtype=np.float32)
    view = frames.transpose(1, 2, 0)
    plain = np.ascontiguousarray(view)
    small = downsample_window(view, FULL, HALF)
    assert small.shape == (3, HALF[0] * HALF[1], 30) and small[0].flags.f_contiguous
    assert np.array_equal(small, downsample_window(plain, FULL, HALF))
    assert np.allclose(small[1], resample_columns(plain[1], FULL, HALF, cv2.INTER_AREA),
                       atol=1e-6)
    assert np.array_equal(resample_frames(plain[2].T, FULL, HALF, cv2.INTER_AREA), small[2].T)
    pixels = PixelSample(FULL, HALF).pixels
    picked = take_pixels(view, pixels)
    assert picked.flags.c_contiguous and np.array_equal(picked, plain[:, pixels])
    assert np.array_equal(take_pixels(plain, pixels), picked)
    assert np.array_equal(take_pixels(plain[0], pixels), plain[0, pixels])
    for small_shape in (HALF, (7, 11)):         # by rows and columns, any ratio
        sample = PixelSample(FULL, small_shape)
        for array in (view, view[0], plain):
            assert np.array_equal(sample.take(array), np.take(array, sample.pixels, axis=-2))


@pytest.mark.parametrize('r', [1, 2, 3])
def test_refit_normal_equations_match_their_definition(r):
    rng = np.random.default_rng(10 + r)
    m, n = 17, 2500                                   # more than one block of pixels
    frames = rng.random((m, 3, n), dtype=np.float32)
    held_out = (rng.random((m, n)) < 0.2) * rng.random((m, n)).astype(np.float32)
    weights = (held_out == 0).astype(np.float64)
    # Each channel its own factors, of different ranks (a channel's SVD may keep fewer).
    temporals = [np.linalg.qr(rng.normal(size=(m, max(1, r - c % 2))))[0].astype(np.float32)
                 for c in range(3)]
    systems = normal_equations(frames, held_out, temporals)
    for channel, (temporal, (gram, rhs)) in enumerate(zip(temporals, systems)):
        data = frames[:, channel].astype(np.float64)
        expected_gram = np.einsum('ji,ja,jb->abi', weights, temporal, temporal)
        expected_rhs = np.einsum('ji,ji,ja->ai', weights, data, temporal)
        k = temporal.shape[1]
        assert gram.shape == (k, k, n) and rhs.shape == (k, n)
        assert np.allclose(gram, expected_gram, rtol=1e-5, atol=1e-5)
        assert np.allclose(rhs, expected_rhs, rtol=1e-5, atol=1e-5)
    # Any memory order of the window, and its frames as separate columns (a
    # snapshot's buffer), give the same sums.
    strided = np.asfortranarray(frames)
    assert np.array_equal(normal_equations(strided, held_out, temporals)[1][1], systems[1][1])
    columns = [frame.copy() for frame in frames]
    assert np.array_equal(normal_equations(columns, held_out, temporals)[1][1], systems[1][1])


@pytest.mark.parametrize('r', [1, 2, 3])
def test_batched_positive_definite_systems_match_numpy(r):
    rng = np.random.default_rng(r)
    factor = rng.normal(size=(500, r, r + 2)).astype(np.float32)
    gram = factor @ factor.transpose(0, 2, 1) + 0.01 * np.eye(r, dtype=np.float32)
    rhs = rng.normal(size=(500, r)).astype(np.float32)
    expected = np.linalg.solve(gram.astype(np.float64), rhs[:, :, None].astype(np.float64))
    x = solve_spd(gram.transpose(1, 2, 0), rhs.T)
    assert x.shape == (r, 500) and x.dtype == np.float32
    assert np.allclose(x.T, expected[:, :, 0], rtol=1e-3, atol=1e-3)


def _low_rank_window(m=24, seed=3):
    """Return a full-size window (1, n, m): pixel-fine texture, a light ramp, a moving block."""
    rng = np.random.default_rng(seed)
    rows, cols, _ = FULL
    texture = rng.uniform(0.2, 0.8, rows * cols).astype(np.float32)     # detail at every pixel
    shading = np.linspace(0.0, 1.0, rows * cols, dtype=np.float32)
    gain = np.linspace(-0.1, 0.1, m, dtype=np.float32)
    truth = texture[:, None] + shading[:, None] * gain[None, :]           # rank 2
    data = truth.copy()
    for frame in range(m):                                                 # 8 x 8 block moving
        image = data[:, frame].reshape(rows, cols)
        left = (2 * frame) % (cols - 8)
        image[20:28, left:left + 8] = 0.05
    data += rng.normal(0, 0.005, data.shape).astype(np.float32)
    return truth, data[None]


def _solve(data, shape, small_shape):
    snapshot = WindowSnapshot(
        data=data, shape=shape, first_id=0, last_id=data.shape[2] - 1, previous=None,
        model=DualGraphMOD(tol=1e-4, max_iter=200), mask_rule=MaskRule(), basis_rank=2,
        decision='adaptive', solve_shape=small_shape)
    return solve_window(snapshot)


def _outside_span(basis, truth):
    """Return the share of ``truth``'s norm outside the basis's column space."""
    return np.linalg.norm(truth - basis @ (basis.T @ truth)) / np.linalg.norm(truth)


def test_carried_basis_reproduces_a_full_size_low_rank_background():
    truth, data = _low_rank_window()
    model = _solve(data, FULL, HALF)
    assert model.shape == FULL and model.solve_shape == HALF
    assert model.basis.shape == (1, FULL[0] * FULL[1], 2)
    assert model.noise.shape == (FULL[0] * FULL[1],)
    # The half-size solve's own L, only upsampled, has lost the pixel-fine
    # texture: its basis leaves a sizeable part of the true background out.
    half_data = downsample_window(data, FULL, HALF)
    half = DualGraphMOD(tol=1e-4, max_iter=200).fit(half_data[0], HALF[:2])
    upsampled = resample_columns(half.background_, HALF, FULL, cv2.INTER_LINEAR)
    upsampled_miss = _outside_span(background_basis(upsampled, 2), truth)
    carried_miss = _outside_span(model.basis[0], truth)
    assert upsampled_miss > 0.1
    assert carried_miss < 0.01
    # The newest background column is the true one, block included: the block
    # is held out of the fit, so it does not leak into the background.
    newest = model.background[:, :, 0].ravel()
    assert np.percentile(np.abs(newest - truth[:, -1]), 99) < 0.02


def test_refit_at_the_solve_size_keeps_what_moved_out_of_background_and_noise():
    # A short solve (5 sweeps; streaming runs 3) leaves a smear of the moving
    # block in L: its residual, and so the noise level, is inflated along the
    # block's path. The refit holds the block's entries out of each pixel's fit.
    truth, data = _low_rank_window()
    rows, cols, _ = FULL
    path = np.zeros((rows, cols), dtype=bool)
    path[20:28, :] = True
    path = path.ravel()
    figures = {}
    for refit in (False, True):
        snapshot = WindowSnapshot(
            data=data, shape=FULL, first_id=0, last_id=data.shape[2] - 1, previous=None,
            model=DualGraphMOD(tol=1e-3, max_iter=5), mask_rule=MaskRule(), basis_rank=2,
            decision='adaptive', solve_shape=FULL, refit_background=refit)
        model = solve_window(snapshot)
        error = np.abs(model.background[:, :, 0].ravel() - truth[:, -1])
        figures[refit] = (np.median(model.noise[path]) / np.median(model.noise[~path]),
                          np.percentile(error[path], 99))
    # Measured: noise on the path 1.27 times that off it, 1.04 refit; the
    # background's 99th-percentile error on the path 0.061, 0.025 refit.
    assert figures[False][0] > 1.15 and figures[True][0] < 1.1
    assert figures[True][1] < 0.6 * figures[False][1]


def test_carried_factors_give_the_backgrounds_columns_and_residuals():
    _, data = _low_rank_window()
    small = downsample_window(data, FULL, HALF)
    half = DualGraphMOD(tol=1e-4, max_iter=200).fit(small[0], HALF[:2])
    carry = carry_backgrounds(data.transpose(2, 0, 1), FULL, [half.background_],
                              small - half.background_[None], HALF, 2)
    coef, temporal = carry.factors[0]
    background = coef @ temporal.T                                       # (n, m)
    assert np.allclose(carry.newest()[:, 0], background[:, -1], atol=1e-6)
    assert np.allclose(carry.mean()[:, 0], background.mean(axis=1), atol=1e-6)
    residuals = carry.residuals(data)
    assert np.allclose(residuals[0], data[0] - background, atol=1e-6)
    pixels = PixelSample(FULL, HALF).pixels
    assert np.array_equal(carry.residuals(data[:, pixels], pixels), residuals[:, pixels])
    # The basis from A (n x r) spans what the SVD of the whole background does.
    basis = carry.bases(2)[0]
    assert np.allclose(basis @ (basis.T @ background), background, atol=1e-4)


def test_an_uncapped_solve_is_the_solve_at_the_frames_size():
    _, data = _low_rank_window()
    capped_above = _solve(data, FULL, FULL)
    plain = _solve(data, FULL, None)
    assert np.array_equal(capped_above.basis, plain.basis)
    assert np.array_equal(capped_above.noise, plain.noise)


@pytest.fixture(scope='module')
def frames():
    return synthetic_scene(n_frames=40, shape=(48, 64), seed=4).frames


def test_detector_solves_capped_and_warm_starts_at_the_solve_size(frames):
    values = dict(config.DEFAULTS, window=8, stride=3, min_frames=3, scale=1.0,
                  solve_pixels=24 * 32, solve_scale=1.0, warm_start=True)
    detector = config.build_detector(config.validate(values))
    models = []
    for frame in frames:
        result = detector.push(frame)
        assert result.mask.shape == (48, 64)
        if detector.solve_due():
            snapshot = detector.snapshot()
            assert snapshot.solve_shape == (24, 32, 3)
            models.append(detector.solve(snapshot))
            assert detector.install(models[-1])
    assert len(models) > 3
    assert all(m.shape == (48, 64, 3) and m.solve_shape == (24, 32, 3) for m in models)
    assert all(m.basis.shape[1] == 48 * 64 for m in models)
    # Later solves start from the previous one (a few sweeps each).
    assert models[-1].states[0].background.shape == (24 * 32, 8)
    # Changing the cap while running: the next solve starts cold, at the new size.
    detector.configure(solve_pixels=48 * 64)
    snapshot = detector.snapshot()
    assert snapshot.solve_shape == (48, 64, 3)
    assert detector.solve(snapshot).solve_shape == (48, 64, 3)
    # The default solve scale halves the processing size whatever the cap.
    detector.configure(solve_scale=0.5)
    assert detector.snapshot().solve_shape == (24, 32, 3)


def _consecutive_window(frames, **values):
    """Return a detector of an 8-frame window of consecutive frames, ``frames`` processed."""
    values = dict(config.DEFAULTS, window=8, stride=3, min_frames=3, memory_spacing=1, **values)
    detector = config.build_detector(config.validate(values))
    for frame in frames:
        detector.process(frame)
    return detector


def test_a_solve_starts_from_its_window_unless_asked_to_warm_start(frames):
    # The iterates of earlier solves are no part of the window: by default a
    # solve reads nothing of the previous model; warm_start starts it there.
    detector = _consecutive_window(frames[:20])
    snapshot = detector.snapshot()
    assert snapshot.previous is not None and not snapshot.warm_start
    alone = solve_window(replace(snapshot, previous=None))
    assert np.array_equal(solve_window(snapshot).background, alone.background)
    warm = solve_window(replace(snapshot, warm_start=True))
    assert not np.allclose(warm.background, alone.background, atol=1e-4)


def test_a_snapshot_holds_its_window_while_frames_go_on(frames):
    # The snapshot hands the solve the buffered columns, stacked in the solve's
    # thread: frames admitted after it (conditionally, the oldest dropped)
    # must not reach its window.
    detector = _consecutive_window(frames[:12])
    snapshot = detector.snapshot()
    expected = np.stack(detector.buffer_.columns(), axis=2).copy()
    for frame in frames[12:30]:
        detector.push(frame)
    assert not isinstance(snapshot.data, np.ndarray)
    assert np.array_equal(snapshot.window(), expected)
    assert snapshot.window() is snapshot.data and snapshot.data.shape[2] == 8
    # Stacked frames-major: each frame's channels are one contiguous block.
    frames = snapshot.window().transpose(2, 0, 1)                        # (m, C, n)
    assert frames.flags.c_contiguous and frames.shape[0] == 8


def _detector_snapshot(frames):
    """Return a snapshot of buffered columns, downscaled and refit as at the defaults."""
    snapshot = _consecutive_window(frames[:14], scale=1.0).snapshot()
    assert snapshot.solve_shape != snapshot.shape and snapshot.refit_background
    return snapshot


def test_a_snapshot_of_columns_solves_as_its_stacked_window(frames):
    # The node hands over columns, stacked frames-major; tests and benchmarks
    # a C-ordered (C, n, m) window. Both solve to the same model.
    snapshot = _detector_snapshot(frames)
    stacked = replace(snapshot, data=np.stack(snapshot.data, axis=2))
    from_columns, from_stack = solve_window(snapshot), solve_window(stacked)
    for name in ('basis', 'background', 'mean_background', 'noise', 'chroma_noise'):
        assert np.allclose(getattr(from_columns, name), getattr(from_stack, name),
                           atol=1e-5), name


def test_a_solve_on_one_kernel_thread_is_the_solve_on_all(frames):
    # solve_threads changes where the kernels run, never what they compute.
    snapshot = _detector_snapshot(frames)
    snapshot.window()
    on_all = solve_window(replace(snapshot))
    with ThreadPoolExecutor(1, initializer=use_threads, initargs=(1,)) as pool:
        assert pool.submit(numba.get_num_threads).result() == 1
        on_one = pool.submit(solve_window, replace(snapshot)).result()
    assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS    # this thread's own
    for name in ('basis', 'background', 'noise', 'chroma_noise'):
        assert np.array_equal(getattr(on_one, name), getattr(on_all, name)), name


def test_column_cache_gives_the_stacked_windows_copies_and_makes_each_once(monkeypatch):
    rng = np.random.default_rng(4)
    shape, small_shape = (48, 64, 3), (20, 27, 3)                   # not an integer ratio
    columns = [rng.random((3, 48 * 64), dtype=np.float32) for _ in range(6)]
    window = np.stack(columns, axis=0).transpose(1, 2, 0)           # as WindowSnapshot.window
    sample = PixelSample(shape, small_shape)
    cache = ColumnCache()
    small = cache.small_window(columns, shape, small_shape)
    assert small[0].flags.f_contiguous
    assert np.array_equal(small, downsample_window(window, shape, small_shape))
    assert np.array_equal(cache.sampled_window(columns, sample), sample.take(window))
    # One column moves in: only its copies are made.
    made = []
    real = resample_frames
    monkeypatch.setattr('dgmod_ros.core.streaming.solve_resolution.resample_frames',
                        lambda *args: made.append(args[0]) or real(*args))
    moved = columns[1:] + [rng.random((3, 48 * 64), dtype=np.float32)]
    cache.keep(moved)
    again = cache.small_window(moved, shape, small_shape)
    assert len(made) == 1 and made[0] is moved[-1]
    assert np.array_equal(again[:, :, :-1], small[:, :, 1:])
    assert id(columns[0]) not in cache._entries


def test_a_snapshot_of_columns_and_their_cache_solves_as_the_stacked_window():
    # The detector hands over its buffered columns and its ColumnCache; the
    # model is the one of the stacked window, before and after a cache hit.
    _, data = _low_rank_window()
    shape = (FULL[0], FULL[1], 3)
    window = np.repeat(data, 3, axis=0) * np.array([1.0, 0.8, 0.6], np.float32)[:, None, None]
    columns = tuple(np.ascontiguousarray(window[:, :, j]) for j in range(window.shape[2]))
    cache = ColumnCache()

    def snapshot(data, column_cache):
        return WindowSnapshot(
            data=data, shape=shape, first_id=0, last_id=len(columns) - 1, previous=None,
            model=DualGraphMOD(tol=1e-3, max_iter=5), mask_rule=MaskRule(), basis_rank=2,
            decision='adaptive', solve_shape=(24, 32, 3), refit_background=True,
            column_cache=column_cache)
    plain = solve_window(snapshot(window, None))
    for _ in range(2):
        cached = solve_window(snapshot(columns, cache))
        for name in ('basis', 'background', 'noise', 'chroma_noise'):
            assert np.array_equal(getattr(cached, name), getattr(plain, name)), name
