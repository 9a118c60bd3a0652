# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Every method the node can run honours the streaming-detector contract.

In the spirit of scikit-learn's ``parametrize_with_checks``: one call sequence,
run against the detector of each method in the parameter table, including a
solve that finishes after a reconfiguration and after a method switch.
"""

from dgmod_ros import config
from dgmod_ros.core.streaming import StreamingDetector
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
    installed, announced = 0, 0
    for frame_id, frame in enumerate(frames[:20]):
        result = detector.push(frame)
        _check_result(detector, result, frame_id)
        announced += result.new_background
        installed += _solve_when_due(detector) is not None
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
