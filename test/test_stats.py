# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's counters and its frozen-background rule, on a clock the test drives."""

from dgmod_ros.stats import DetectorStats
import pytest


class FakeClock:
    """Seconds that move only when the test says so."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


@pytest.fixture
def clock():
    return FakeClock()


def test_a_due_solve_that_never_finishes_is_overdue_while_frames_arrive(clock):
    stats = DetectorStats(clock=clock)
    stats.received()
    stats.solve_due()
    for _ in range(11):                         # a frame a second, the solve stuck
        clock.now += 1.0
        stats.received()
        stats.solve_due()                       # still due: the wait keeps its start
    assert stats.solve_wait() == 11.0
    assert stats.solve_overdue(10.0) and not stats.solve_overdue(12.0)
    assert not stats.solve_overdue(0.0)         # 0 disables the rule
    assert stats.snapshot()['solve_wait_s'] == 11.0


@pytest.mark.parametrize('finish', ['solved', 'failed', 'discarded'])
def test_any_finished_solve_ends_the_wait(clock, finish):
    stats = DetectorStats(clock=clock)
    stats.received()
    stats.solve_due()
    clock.now += 20.0
    stats.received()
    assert stats.solve_overdue(10.0)
    {'solved': lambda: stats.solved(1.0, 5, 0), 'failed': lambda: stats.failed('NaN'),
     'discarded': stats.discarded}[finish]()
    assert stats.solve_wait() == 0.0 and not stats.solve_overdue(10.0)


def test_a_camera_that_stopped_is_not_a_stuck_solver(clock):
    stats = DetectorStats(clock=clock)
    stats.received()
    stats.solve_due()
    clock.now += 60.0                            # no frames for a minute
    assert stats.solve_wait() == 60.0 and not stats.solve_overdue(10.0)
    stats.received()                             # frames again, the solve still stuck
    assert stats.solve_overdue(10.0)


def test_counters_add_up():
    stats = DetectorStats()
    for _ in range(5):
        stats.received()
    stats.masked(0.002)
    stats.masked(0.004)
    stats.drop('encoding')
    figures = stats.snapshot()
    assert (figures['frames_in'], figures['masks_out'], figures['frames_dropped']) == (5, 2, 1)
    assert figures['dropped_encoding'] == 1
    assert figures['mask_latency_p50_ms'] == pytest.approx(3.0)
