# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The node's counters and its frozen-background rule, on a clock the test drives."""

from dgmod_ros.stats import DetectorStats
import numpy as np
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


def feed(stats, clock, stamps, period=1 / 30):
    """Receive one frame per ``period`` of the clock with the given header stamps."""
    for stamp in stamps:
        stats.received(stamp)
        clock.now += period


def test_received_rate_follows_the_arrivals(clock):
    stats = DetectorStats(clock=clock, rate_window=31)
    assert np.isnan(stats.snapshot()['received_rate_hz'])
    feed(stats, clock, [None] * 100, period=0.04)
    assert stats.snapshot()['received_rate_hz'] == pytest.approx(25.0)
    feed(stats, clock, [None] * 40, period=0.1)           # the window forgets the old rate
    assert stats.snapshot()['received_rate_hz'] == pytest.approx(10.0)


def test_gaps_in_the_stamps_are_counted_with_the_largest(clock):
    stats = DetectorStats(clock=clock)
    stamps = list(1000.0 + np.arange(60) / 30)             # 30 frames/s, no gap
    stamps += list(stamps[-1] + 3 / 30 + np.arange(30) / 30)    # two frames lost
    stamps += list(stamps[-1] + 11 / 30 + np.arange(30) / 30)   # ten frames lost
    feed(stats, clock, stamps)
    figures = stats.snapshot()
    assert figures['stamp_gaps'] == 2
    assert figures['stamp_gap_largest_ms'] == pytest.approx(1e3 * 11 / 30)
    assert figures['stamp_period_median_ms'] == pytest.approx(1e3 / 30)
    assert figures['frames_in'] == 120


def test_jitter_below_the_factor_and_repeated_stamps_are_no_gaps(clock):
    stats = DetectorStats(clock=clock)
    rng = np.random.default_rng(0)
    periods = (1 + rng.uniform(-0.3, 0.3, 200)) / 30       # +-30% jitter < 1.5x
    stamps = list(50.0 + np.cumsum(periods))
    stamps.insert(100, stamps[99])                         # a repeated stamp
    stamps.insert(150, stamps[140])                        # one going back
    feed(stats, clock, stamps)
    figures = stats.snapshot()
    assert figures['stamp_gaps'] == 0 and figures['stamp_gap_largest_ms'] == 0.0
    assert figures['stamps_not_increasing'] == 2


def test_the_first_intervals_decide_nothing(clock):
    stats = DetectorStats(clock=clock)
    feed(stats, clock, [0.0, 1.0, 1.1, 1.2])               # no median yet: no gap
    assert stats.snapshot()['stamp_gaps'] == 0
