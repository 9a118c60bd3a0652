# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's health rules without ROS: the foreground-jump watch, the figures, the problems."""

from dgmod_ros import health
from dgmod_ros.stats import DetectorStats
import numpy as np


def _mask(share, size=100):
    mask = np.zeros(size, np.uint8)
    mask[:int(round(share * size))] = 255
    return mask.reshape(10, -1)


def test_a_jump_is_a_change_of_share_beyond_the_threshold_between_consecutive_masks():
    watch = health.ForegroundWatch()
    assert watch.observe(_mask(0.1), 0.3) is None           # the first: nothing to compare
    assert watch.observe(_mask(0.35), 0.3) is None          # 25 points: no jump
    assert watch.observe(_mask(0.7), 0.3) == (0.35, 0.7)
    assert watch.jumps == 1 and watch.share == 0.7
    watch.reset()                                           # the window restarted
    assert watch.share is None
    assert watch.observe(_mask(0.0), 0.3) is None and watch.jumps == 1


def test_each_jump_is_reported_once():
    watch = health.ForegroundWatch()
    for share in (0.0, 0.5, 0.0):
        watch.observe(_mask(share), 0.3)
    assert watch.unreported() == 2
    assert watch.unreported() == 0
    watch.observe(_mask(0.9), 0.3)
    assert watch.unreported() == 1


def test_the_jump_warning_names_both_shares():
    line = health.jump_warning(0.1, 0.65)
    assert line.startswith('foreground share jumped from 10% to 65% of the frame')
    assert '~/reset_background' in line


class _Detector:
    def status(self):
        return {'window_frames': 7, 'model_ready': True, 'scene_changes': 0}


class _Depth:
    def statistics(self):
        return {'depth_in': 3, 'depth_model_ready': False}


class _Worker:
    callback_errors = 2


def test_the_figures_hold_the_counters_the_watch_and_the_detector():
    stats = DetectorStats(clock=lambda: 0.0)
    stats.received()
    watch = health.ForegroundWatch()
    watch.observe(_mask(0.123456), 0.3)
    figures = health.node_figures(stats, 'active', 4, watch, _Detector().status,
                                  worker=_Worker())
    assert figures['frames_in'] == 1 and figures['lifecycle_state'] == 'active'
    assert figures['frames_ignored_inactive'] == 4 and figures['foreground_jumps'] == 0
    assert figures['foreground_share'] == 0.12 and figures['window_frames'] == 7
    assert figures['model_ready'] and figures['worker_callback_errors'] == 2
    keys = list(figures)
    assert keys.index('stamps_not_increasing') < keys.index('lifecycle_state') \
        < keys.index('foreground_share') < keys.index('window_frames')


def test_without_a_detector_the_window_is_empty_and_depth_only_reads_the_depth_model():
    watch = health.ForegroundWatch()
    figures = health.node_figures(DetectorStats(), 'inactive', 0, watch, lambda: None)
    assert figures['window_frames'] == 0 and not figures['model_ready']
    assert 'foreground_share' not in figures and 'worker_callback_errors' not in figures
    figures = health.node_figures(DetectorStats(), 'active', 0, watch, _Detector().status,
                                  _Depth(), depth_only=True)
    assert figures['depth_in'] == 3 and figures['model_ready'] is False


def _figures(**changes):
    figures = {'frames_dropped': 0, 'solve_failures': 0, 'model_ready': True,
               'solve_wait_s': 0.0}
    figures.update(changes)
    return figures


def test_no_problem_is_ok():
    found = health.problems(_figures(), 'active', False, 10.0)
    assert found == [] and health.status_message(found) == health.ALL_WELL


def test_the_problems_come_in_order_and_join_into_one_message():
    found = health.problems(_figures(frames_dropped=3, solve_failures=1, model_ready=False,
                                     solve_wait_s=12.4),
                            'active', True, 10.0, malformed_depth=2, new_jumps=1,
                            foreground_jump=0.3)
    assert found == [
        '3 frames dropped', '1 solves failed', 'warming up: no background model yet',
        'no window solve finished for 12 s while frames arrive (solve_timeout 10.0 s): the '
        'background is frozen',
        '2 malformed depth images or camera infos dropped',
        'foreground share jumped 1 times by more than 30% of the frame (camera moved, '
        'lights?)']
    assert health.status_message(found) == '; '.join(found)


def test_a_node_not_active_says_so_instead_of_warming_up():
    found = health.problems(_figures(model_ready=False), 'inactive', False, 10.0)
    assert found == ['inactive: not masking frames']
