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

    """

    def __init__(self, latency_window=1000, clock=time.monotonic):
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

    def received(self):
        """Count one incoming message."""
        with self._lock:
            self.frames_in += 1
            self._last_frame = self._clock()

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
        with self._lock:
            figures = {'frames_in': self.frames_in, 'masks_out': self.masks_out,
                       'frames_dropped': sum(self.dropped.values()),
                       'solves': self.solves, 'solve_failures': self.solve_failures,
                       'solves_discarded': self.solves_discarded,
                       'solve_wait_s': wait,
                       'window_resets': self.resets,
                       'mask_latency_p50_ms': 1e3 * p50, 'mask_latency_p95_ms': 1e3 * p95}
            figures.update({f'dropped_{k}': v for k, v in sorted(self.dropped.items())})
            figures.update({f'last_solve_{k}': v for k, v in self.last_solve.items()})
            if self.last_error:
                figures['last_solve_error'] = self.last_error
        return figures
