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
    h = DetectorHarness(**PARAMETERS)
    yield h
    h.close()


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
