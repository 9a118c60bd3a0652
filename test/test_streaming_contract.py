# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Every method the node can run honours the streaming-detector contract.

In the spirit of scikit-learn's ``parametrize_with_checks``: one call sequence,
run against the detector of each method in the parameter table, including a
solve that finishes after a reconfiguration and after a method switch.
"""

from concurrent.futures import Executor, Future, ThreadPoolExecutor

import cv2
from dgmod_ros import config
from dgmod_ros.core.streaming import SolverFailure, StreamingDetector
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
import pytest

METHODS = config.BY_NAME['method'].choices
SHAPE = (24, 32)


def _values(method, **changes):
    values = dict(config.DEFAULTS, method=method, window=8, stride=3, min_frames=3)
    values.update(changes)
    return config.validate(values)


@pytest.fixture(scope='module')
def frames():
    return synthetic_scene(n_frames=30, shape=SHAPE, seed=4).frames


def _check_result(detector, result, frame_id=None):
    assert result.mask.shape == SHAPE and result.mask.dtype == np.uint8
    assert set(np.unique(result.mask)) <= {0, 255}
    assert frame_id is None or result.frame_id == frame_id
    if result.new_background:
        background = detector.background_image()
        assert background.shape[:2] == SHAPE and background.dtype == np.float32
        assert background.min() >= 0 and background.max() <= 1


def _solve_when_due(detector):
    """Run the asynchronous protocol in line: return the installed model or None."""
    if not detector.solve_due():
        return None
    model = detector.solve(detector.snapshot())
    assert detector.install(model)
    return model


def _window_with_solve_in_flight(method, frames):
    """Return (detector, snapshot) of a window method with a due solve taken."""
    detector = config.build_detector(_values(method))
    for frame in frames:
        detector.push(frame)
        if detector.solve_due():
            return detector, detector.snapshot()
    raise AssertionError('no solve became due')


@pytest.mark.parametrize('method', METHODS)
def test_push_solve_install_sequence(method, frames):
    detector = config.build_detector(_values(method))
    assert isinstance(detector, StreamingDetector)
    assert detector.background_image() is None          # nothing seen yet
    assert detector.processing_size() is None
    installed, announced = 0, 0
    for frame_id, frame in enumerate(frames[:20]):
        result = detector.push(frame)
        _check_result(detector, result, frame_id)
        announced += result.new_background
        installed += _solve_when_due(detector) is not None
    assert detector.processing_size() == (SHAPE[0] // 2, SHAPE[1] // 2)     # scale 0.5
    status = detector.status()
    assert set(status) == {'window_frames', 'model_ready', 'scene_changes'}
    assert status['model_ready']
    # Every window solve brings one background; a subtractor has one every stride.
    assert announced == (installed if installed else 20 // 3)
    result, _ = detector.process(frames[20])
    _check_result(detector, result, 20)
    detector.drop_warm_start()
    detector.reset()
    assert detector.background_image() is None
    _check_result(detector, detector.push(frames[21]), 0)


@pytest.mark.parametrize('method', METHODS)
@pytest.mark.parametrize('change', ['configure', 'reset'])
def test_solve_finished_after_a_reconfigure_is_discarded(method, change, frames):
    detector = config.build_detector(_values(method))
    in_flight = None
    for frame in frames:
        detector.push(frame)
        if detector.solve_due():
            in_flight = detector.solve(detector.snapshot())
            break
    if change == 'configure':
        detector.configure(**config.detector_settings(_values(method, mask_k=4.0)))
    else:
        detector.reset()
    if in_flight is None:                      # a subtractor: another detector's solve
        _, snapshot = _window_with_solve_in_flight('median', frames)
        in_flight = config.build_detector(_values('median')).solve(snapshot)
    ready = detector.status()['model_ready']
    assert not detector.install(in_flight)
    assert detector.solves_discarded_ == 1
    assert detector.status()['model_ready'] == ready          # nothing installed
    for frame in frames[:12]:                                 # and it goes on
        _check_result(detector, detector.push(frame))
        _solve_when_due(detector)


@pytest.mark.parametrize('method', METHODS)
@pytest.mark.parametrize('direction', ['switched_to', 'switched_from'])
def test_solve_finished_after_a_method_switch_is_discarded(method, direction, frames):
    other = 'median' if method != 'median' else 'dgmod'
    old_method, new_method = (other, method) if direction == 'switched_to' else (method, other)
    detector = config.build_detector(_values(old_method))
    snapshot = None
    for frame in frames:
        detector.push(frame)
        if detector.solve_due():
            snapshot = detector.snapshot()
            break
    replaced = config.update_detector(detector, _values(new_method), _values(old_method))
    if snapshot is None:                       # the old method solves no windows
        return
    # The worker solves with the detector that took the snapshot; the result
    # comes back to whatever runs now.
    solved = detector.solve(snapshot)
    assert not replaced.install(solved)
    replaced.drop_warm_start()                 # what the node's error path calls: harmless
    for frame in frames[:12]:
        _check_result(replaced, replaced.push(frame))
        _solve_when_due(replaced)


@pytest.mark.parametrize('method', METHODS)
def test_bad_reconfiguration_changes_nothing(method, frames):
    detector = config.build_detector(_values(method))
    detector.push(frames[0])
    with pytest.raises(ValueError, match='unknown parameters: nonsense'):
        detector.configure(nonsense=1)
    with pytest.raises(ValueError, match='scale'):
        detector.configure(scale=2.0)
    assert detector.scale == 0.5
    _check_result(detector, detector.push(frames[1]), 1)


class _LastMomentExecutor(Executor):
    """Run each solve only when its result is asked for: the slowest solve that is on time."""

    def submit(self, fn, *args, **kwargs):
        return _LastMomentFuture(fn, args, kwargs)


class _LastMomentFuture(Future):
    def __init__(self, fn, args, kwargs):
        super().__init__()
        self._job = (fn, args, kwargs)

    def result(self, timeout=None):
        if self._job is not None:
            fn, args, kwargs = self._job
            self._job = None
            try:
                self.set_result(fn(*args, **kwargs))
            except Exception as error:  # noqa: B902 - handed over like a real future
                self.set_exception(error)
        return super().result(timeout)


def _process_all(method, frames, executor, **changes):
    cv2.setRNGSeed(0)       # knn samples with OpenCV's global generator
    detector = config.build_detector(_values(method, **changes))
    masks, installed_at, started_early_at = [], [], []
    for frame_id, frame in enumerate(frames):
        result, solved = detector.process(frame, executor=executor)
        masks.append(result.mask)
        if solved is not None:
            installed_at.append(frame_id)
        if detector.solve_in_flight() and not detector.solve_lag:
            started_early_at.append(frame_id)
    return np.stack(masks), installed_at, started_early_at


@pytest.mark.parametrize('method', METHODS)
def test_install_rule_gives_the_same_masks_whatever_the_solve_speed(method, frames):
    # stride 3, solve_lag 2: a solve taken at frame t is installed before frame t + 2.
    inline, installed, _ = _process_all(method, frames, None, solve_lag=2)
    with ThreadPoolExecutor(max_workers=1) as pool:
        threaded, threaded_installed, _ = _process_all(method, frames, pool, solve_lag=2)
    late, late_installed, _ = _process_all(method, frames, _LastMomentExecutor(), solve_lag=2)
    assert np.array_equal(inline, threaded) and np.array_equal(inline, late)
    assert installed == threaded_installed == late_installed
    if config.detector_class(_values(method)) is config.SlidingWindowDetector:
        # First solve at min_frames = 3, installed at once (no model yet); then a
        # snapshot every stride = 3 frames (6, 9, 12), each installed solve_lag = 2 later.
        assert installed[:4] == [3, 8, 11, 14]
    else:
        assert installed == []


@pytest.mark.parametrize('method', METHODS)
def test_early_start_gives_the_masks_of_solving_in_line(method, frames):
    # solve_lag 0: with an executor, a solve whose window is final starts before it
    # is due (the window of 8 is full at frame 7; then one admission every 10 frames).
    inline, installed, started_early = _process_all(method, frames, None, solve_lag=0)
    assert started_early == []
    late, late_installed, late_early = _process_all(method, frames, _LastMomentExecutor(),
                                                    solve_lag=0)
    assert np.array_equal(inline, late) and installed == late_installed
    if config.detector_class(_values(method)) is config.SlidingWindowDetector:
        assert installed[:4] == [3, 6, 9, 12]
        # Admissions at 0-7 (filling), then 17, 27: the solves due at 9, 12 and 15
        # start as soon as the one before is installed (in flight from frame 8 on);
        # the one due at 18 would see frame 17's admission, so it waits for its frame.
        assert late_early[:8] == [8, 9, 10, 11, 12, 13, 14, 19]
    else:
        assert late_early == []


def test_push_installs_a_late_solve_at_the_first_frame_after_it_ends(frames):
    detector = config.build_detector(_values('dgmod', solve_lag=2))
    for frame in frames[:3]:
        detector.push(frame)
    assert detector.solve_due()
    first = detector.snapshot()
    detector.track_solve(first, _finished(detector.solve(first)))
    assert not detector.solve_due()                    # one solve in flight at a time
    assert detector.push(frames[3]).installed is not None   # no model yet: at once
    for frame in frames[4:6]:
        detector.push(frame)
    assert detector.solve_due()
    snapshot = detector.snapshot()
    future = Future()
    detector.track_solve(snapshot, future)
    for frame in frames[6:9]:                          # its frame (8) passes: still running
        result = detector.push(frame)
        assert result.installed is None and not detector.solve_due()
    future.set_result(detector.solve(snapshot))
    assert detector.push(frames[9]).installed is future.result()


def test_a_solve_in_flight_is_discarded_by_a_reconfigure(frames):
    detector = config.build_detector(_values('dgmod', solve_lag=2))
    for frame in frames[:3]:
        detector.push(frame)
    snapshot = detector.snapshot()
    future = Future()
    detector.track_solve(snapshot, future)
    detector.configure(pixel_k=5.0)
    assert not detector.solve_in_flight() and detector.solves_discarded_ == 1
    future.set_result(detector.solve(snapshot))
    assert detector.push(frames[3]).installed is None
    assert detector.solve_due()                         # the next solve starts at once


def test_failed_solve_is_reported_at_its_frame(frames):
    detector = config.build_detector(_values('dgmod', solve_lag=2))
    for frame in frames[:3]:
        detector.push(frame)
    detector.track_solve(snapshot := detector.snapshot(), _finished(detector.solve(snapshot)))
    for frame in frames[3:6]:                            # installed at 3, due again at 6
        detector.push(frame)
    assert detector.background_model_ is not None and detector.solve_due()
    snapshot = detector.snapshot()
    failed = Future()
    failed.set_exception(SolverFailure('window solve produced non-finite values'))
    detector.track_solve(snapshot, failed)
    assert detector.push(frames[6]).solve_error is None
    result = detector.push(frames[7])
    assert result.solve_error and result.installed is None
    assert detector.background_model_.states == []      # the next solve starts cold


def test_solve_lag_above_the_stride_waits_the_stride(frames):
    # One solve is in flight at a time and the next is due a stride later:
    # a longer lag (the default 5 with stride 3) installs at the stride.
    at_stride = _process_all('dgmod', frames, None, solve_lag=3)
    longer = _process_all('dgmod', frames, None, solve_lag=4)
    assert np.array_equal(at_stride[0], longer[0]) and at_stride[1] == longer[1]
    assert at_stride[1][:3] == [3, 9, 12]
    with pytest.raises(ValueError, match='solve_lag'):
        config.build_detector(_values('dgmod', solve_lag=-1))


def _finished(model):
    future = Future()
    future.set_result(model)
    return future
