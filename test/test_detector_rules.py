# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's per-frame rules without ROS: the encoding-change restart and the solve schedule."""

from types import SimpleNamespace

from dgmod_ros import config
from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.detector_rules import EncodingWatch, mask_frame, solve_job
from fresh_process import fresh_python
import pytest


def test_an_encoding_change_is_reported_with_the_previous_encoding():
    watch = EncodingWatch()
    assert watch.changed('rgb8') is None                    # the first frame
    assert watch.changed('rgb8') is None
    assert watch.changed('32FC1') == 'rgb8'
    assert watch.changed('32FC1') is None and watch.encoding == '32FC1'
    watch.reset()                                           # a new detector
    assert watch.changed('mono8') is None


class _Worker:
    """A SolveWorker that only records what it was handed (no thread)."""

    def __init__(self, busy=False):
        self.busy = busy
        self.jobs = []

    def submit(self, job):
        self.jobs.append(job)
        return True


class _Detector:
    """Records the calls of the streaming contract that mask_frame makes."""

    def __init__(self, due):
        self.due = due
        self.calls = []

    def process(self, *args):
        self.calls.append(('process',) + args)
        return 'result', 'model'

    def push(self, *args):
        self.calls.append(('push',) + args)
        return SimpleNamespace(installed='installed model')

    def solve_due(self):
        return self.due

    def snapshot(self):
        return 'snapshot'

    def solve(self, snapshot):
        return ('solved', snapshot)


def test_sync_mode_lets_the_detector_solve_in_line():
    detector, worker = _Detector(due=True), _Worker()
    assert mask_frame(detector, 'frame', 'bgr', 255.0, 'sync', worker) == ('result', 'model')
    assert detector.calls == [('process', 'frame', 'bgr', 255.0)] and worker.jobs == []


@pytest.mark.parametrize('due, busy, submitted', [(False, False, False), (True, False, True),
                                                  (True, True, False)])
def test_async_mode_hands_a_due_solve_to_an_idle_worker(due, busy, submitted):
    detector, worker, waits = _Detector(due), _Worker(busy), []
    result, solved = mask_frame(detector, 'frame', 'rgb', None, 'async', worker,
                                lambda: waits.append(1))
    assert detector.calls == [('push', 'frame', 'rgb', None)]
    assert solved == 'installed model' == result.installed
    assert waits == ([1] if due else [])                    # the wait starts even if busy
    assert worker.jobs == ([(detector, 'snapshot')] if submitted else [])
    if submitted:
        assert solve_job(worker.jobs[0]) == ('solved', 'snapshot')


def test_async_with_a_real_detector_solves_where_sync_does():
    values = dict(config.DEFAULTS, window=10, stride=5, min_frames=4)
    scene = synthetic_scene(n_frames=12, shape=(24, 32), seed=1)
    detector, worker, due = config.build_detector(values), _Worker(), []
    for index, frame in enumerate(scene.frames):
        mask_frame(detector, frame, 'rgb', None, 'async', worker, lambda: due.append(index))
        while worker.jobs:                                  # solved at once, as if instantly
            job = worker.jobs.pop()
            assert detector.install(solve_job(job))
    assert due[0] == values['min_frames'] - 1 and detector.status()['model_ready']


def test_the_nodes_rules_import_no_ros():
    # A fresh process: the node's modules imported by other tests would hide it.
    script = ('import sys\n'
              'import dgmod_ros.detector_rules, dgmod_ros.health, dgmod_ros.node_parameters\n'
              'import dgmod_ros.solve_worker, dgmod_ros.stats\n'
              'print(sorted(m for m in sys.modules if m.split(".")[0] in\n'
              '             ("rclpy", "sensor_msgs", "diagnostic_msgs", "rcl_interfaces")))\n')
    assert fresh_python(script).strip() == '[]'
