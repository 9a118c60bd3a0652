# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
A solve in flight while the node's detector is replaced or reconfigured (issue 11).

The solve blocks on an event, so the race is reproduced deterministically: the
parameter change happens while the solve is certainly running, the solve ends
when the test says so.
"""

import threading

from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.stats import DetectorStats
from diagnostic_msgs.msg import DiagnosticStatus
import pytest
from rclpy.parameter import Parameter
from ros_harness import DetectorHarness, image_message

PARAMETERS = {'window': 8, 'stride': 3, 'min_frames': 3, 'solve_mode': 'async'}


class BlockingModel:
    """A window model whose fit waits until the test releases it."""

    def __init__(self, model):
        self.model = model
        self.started = threading.Event()
        self.release = threading.Event()

    def fit(self, data, frame_shape, init=None):
        self.started.set()
        assert self.release.wait(30.0), 'the test never released the solve'
        return self.model.fit(data, frame_shape, init)


@pytest.fixture(scope='module')
def frames():
    return synthetic_scene(n_frames=40, shape=(48, 64), seed=6).frames


@pytest.fixture
def harness():
    with DetectorHarness(**PARAMETERS) as h:
        yield h


def _send(harness, frame):
    harness.send(image_message(frame, 'rgb8'))


def _start_blocked_solve(harness, frames):
    """Send frames until a solve is in flight in a model that blocks; return the model."""
    _send(harness, frames[0])                  # the detector builds its model
    with harness.node._lock:
        blocking = BlockingModel(harness.node._detector.model_)
        harness.node._detector.model_ = blocking
    for frame in frames[1:]:
        _send(harness, frame)
        if blocking.started.wait(0.0 if not harness.node._worker.busy else 10.0):
            return blocking
    raise AssertionError('no solve started')


@pytest.mark.parametrize('change', [
    [Parameter('method', value='knn')],                                  # another class
    [Parameter('method', value='median')],                               # same class
    [Parameter('mask_k', value=4.0)],                                    # reconfigured
])
def test_a_solve_that_ends_after_a_change_is_discarded_and_solving_goes_on(
        harness, frames, change):
    blocking = _start_blocked_solve(harness, frames)
    assert harness.node._worker.busy
    assert all(r.successful for r in harness.node.set_parameters(change))
    blocking.release.set()
    harness.wait_for_solves()
    figures = harness.node.statistics()
    assert figures['solves_discarded'] == 1 and figures['solves'] == 0
    assert figures['solve_failures'] == 0 and figures['worker_callback_errors'] == 0
    # Back to dgmod: windows are solved again (the worker is alive, not busy).
    assert all(r.successful for r in
               harness.node.set_parameters([Parameter('method', value='dgmod')]))
    for frame in frames[:12]:
        _send(harness, frame)
        harness.wait_for_solves()
    figures = harness.node.statistics()
    assert figures['solves'] >= 3 and not harness.node._worker.busy
    assert len(harness.backgrounds) >= 3


def test_a_stuck_solve_turns_diagnostics_to_warn_while_frames_arrive(harness, frames):
    clock = FakeClock()
    harness.node._stats = DetectorStats(clock=clock)
    blocking = _start_blocked_solve(harness, frames)
    assert 'no window solve finished' not in harness.node.diagnostic_status().message
    for frame in frames[10:22]:                 # a frame a second, the solve stuck
        clock.now += 1.0
        _send(harness, frame)
    status = harness.node.diagnostic_status()
    assert status.level == DiagnosticStatus.WARN
    assert 'no window solve finished for 12 s' in status.message
    blocking.release.set()
    harness.wait_for_solves()
    _send(harness, frames[22])                  # the solved background is in use
    status = harness.node.diagnostic_status()
    assert status.level == DiagnosticStatus.OK, status.message


class FakeClock:
    """Seconds that move only when the test says so."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now
