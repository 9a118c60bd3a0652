# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Counters and latency statistics the node reports in /diagnostics (no ROS import)."""

from collections import Counter, deque
import threading
import time

import numpy as np


class DetectorStats:
    """
    Thread-safe counters of what came in, what went out and what was dropped.

    Every received message is either masked (``masks_out``) or dropped with
    a reason (``dropped[reason]``), so ``frames_in == masks_out + sum(dropped)``
    once the callbacks in flight have returned.

    Parameters
    ----------
    latency_window : int, default=1000
        Mask latencies kept for the percentiles.
    clock : callable, default=time.monotonic
        Seconds; tests pass their own to make the solve-timeout rule deterministic.
    rate_window : int, default=150
        Recent arrivals (received frame rate) and stamp intervals (median
        period) kept; 5 s at 30 frames/s.
    gap_factor : float, default=1.5
        An interval between consecutive input stamps longer than
        ``gap_factor`` times the median recent interval is a gap (frames lost
        before the node: transport, driver).

    """

    def __init__(self, latency_window=1000, clock=time.monotonic, rate_window=150,
                 gap_factor=1.5):
        self._lock = threading.Lock()
        self._clock = clock
        self.frames_in = 0
        self.masks_out = 0
        self.dropped = Counter()
        self.solves = 0
        self.solve_failures = 0
        self.solves_discarded = 0
        self.resets = 0
        self.last_solve = {}
        self.last_error = ''
        self._latencies = deque(maxlen=latency_window)
        self._last_frame = None         # clock time of the last received message
        self._waiting_since = None      # clock time a due solve began to wait, if one does
        self._gap_factor = gap_factor
        self._arrivals = deque(maxlen=rate_window)
        self._periods = deque(maxlen=rate_window)
        self._last_stamp = None
        self.stamp_gaps = 0
        self.largest_stamp_gap = 0.0
        self.stamps_not_increasing = 0

    def received(self, stamp=None):
        """
        Count one incoming message; ``stamp`` is its header stamp in seconds (None: unknown).

        Stamps feed the gap count: an interval longer than ``gap_factor`` times
        the median of the recent intervals (at least 5 of them) is one gap. A
        stamp that does not increase is counted apart and skipped.
        """
        with self._lock:
            self.frames_in += 1
            self._last_frame = self._clock()
            self._arrivals.append(self._last_frame)
            if stamp is None:
                return
            stamp = float(stamp)
            if self._last_stamp is not None:
                interval = stamp - self._last_stamp
                if interval <= 0.0:
                    self.stamps_not_increasing += 1
                    return
                if len(self._periods) >= 5 and \
                        interval > self._gap_factor * float(np.median(self._periods)):
                    self.stamp_gaps += 1
                    self.largest_stamp_gap = max(self.largest_stamp_gap, interval)
                self._periods.append(interval)
            self._last_stamp = stamp

    def received_rate(self):
        """Return the received frame rate (1/s) over the recent arrivals, or nan."""
        with self._lock:
            if len(self._arrivals) < 2:
                return float('nan')
            span = self._arrivals[-1] - self._arrivals[0]
            count = len(self._arrivals) - 1
        return count / span if span > 0 else float('nan')

    def drop(self, reason):
        """Count one message dropped for ``reason``."""
        with self._lock:
            self.dropped[reason] += 1

    def masked(self, latency_s):
        """Count one mask published ``latency_s`` after its frame arrived."""
        with self._lock:
            self.masks_out += 1
            self._latencies.append(latency_s)

    def solve_due(self):
        """Note that the detector wants a window solve (the wait starts, if not yet)."""
        with self._lock:
            if self._waiting_since is None:
                self._waiting_since = self._clock()

    def _finished(self):
        self._waiting_since = None

    def solved(self, seconds, iterations, info):
        """Count one successful window solve."""
        with self._lock:
            self.solves += 1
            self.last_solve = {'seconds': seconds, 'iterations': iterations, 'info': info}
            self._finished()

    def failed(self, message):
        """Count one failed window solve."""
        with self._lock:
            self.solve_failures += 1
            self.last_error = message
            self._finished()

    def discarded(self):
        """Count one solve whose result came back for a replaced or reconfigured detector."""
        with self._lock:
            self.solves_discarded += 1
            self._finished()

    def window_reset(self):
        """Count one restart of the window (frame size or encoding change)."""
        with self._lock:
            self.resets += 1

    def solve_wait(self):
        """
        Return the seconds since a due solve began to wait with none finished (0 if none waits).

        A solve that ends in any way (installed, failed, discarded) ends the wait.
        """
        with self._lock:
            if self._waiting_since is None:
                return 0.0
            return self._clock() - self._waiting_since

    def solve_overdue(self, timeout):
        """
        Tell whether no solve has finished for over ``timeout`` s while frames arrive.

        Frames arrive when the last one came within ``timeout``; a camera that
        stopped is not a stuck solver. ``timeout <= 0`` disables the rule.
        """
        if timeout <= 0:
            return False
        wait = self.solve_wait()
        with self._lock:
            recent = (self._last_frame is not None
                      and self._clock() - self._last_frame <= timeout)
        return wait > timeout and recent

    def latency_percentiles(self):
        """Return (p50, p95) mask latency in seconds over the recent frames, or (nan, nan)."""
        with self._lock:
            values = np.array(self._latencies)
        if values.size == 0:
            return float('nan'), float('nan')
        return float(np.percentile(values, 50)), float(np.percentile(values, 95))

    def snapshot(self):
        """Return a plain dict of every figure, for diagnostics and tests."""
        p50, p95 = self.latency_percentiles()
        wait = self.solve_wait()
        rate = self.received_rate()
        with self._lock:
            period = float(np.median(self._periods)) if self._periods else float('nan')
            figures = {'frames_in': self.frames_in, 'masks_out': self.masks_out,
                       'frames_dropped': sum(self.dropped.values()),
                       'solves': self.solves, 'solve_failures': self.solve_failures,
                       'solves_discarded': self.solves_discarded,
                       'solve_wait_s': wait,
                       'window_resets': self.resets,
                       'mask_latency_p50_ms': 1e3 * p50, 'mask_latency_p95_ms': 1e3 * p95,
                       'received_rate_hz': rate, 'stamp_period_median_ms': 1e3 * period,
                       'stamp_gaps': self.stamp_gaps,
                       'stamp_gap_largest_ms': 1e3 * self.largest_stamp_gap,
                       'stamps_not_increasing': self.stamps_not_increasing}
            figures.update({f'dropped_{k}': v for k, v in sorted(self.dropped.items())})
            figures.update({f'last_solve_{k}': v for k, v in self.last_solve.items()})
            if self.last_error:
                figures['last_solve_error'] = self.last_error
        return figures
