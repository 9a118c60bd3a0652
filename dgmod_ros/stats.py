# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Counters and latency statistics the node reports in /diagnostics (no ROS import)."""

from collections import Counter, deque
import threading

import numpy as np


class DetectorStats:
    """
    Thread-safe counters of what came in, what went out and what was dropped.

    Every received message is either masked (``masks_out``) or dropped with
    a reason (``dropped[reason]``), so ``frames_in == masks_out + sum(dropped)``
    once the callbacks in flight have returned.
    """

    def __init__(self, latency_window=1000):
        self._lock = threading.Lock()
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

    def received(self):
        """Count one incoming message."""
        with self._lock:
            self.frames_in += 1

    def drop(self, reason):
        """Count one message dropped for ``reason``."""
        with self._lock:
            self.dropped[reason] += 1

    def masked(self, latency_s):
        """Count one mask published ``latency_s`` after its frame arrived."""
        with self._lock:
            self.masks_out += 1
            self._latencies.append(latency_s)

    def solved(self, seconds, iterations, info):
        """Count one successful window solve."""
        with self._lock:
            self.solves += 1
            self.last_solve = {'seconds': seconds, 'iterations': iterations, 'info': info}

    def failed(self, message):
        """Count one failed window solve."""
        with self._lock:
            self.solve_failures += 1
            self.last_error = message

    def discarded(self):
        """Count one solve whose result came back for a replaced or reconfigured detector."""
        with self._lock:
            self.solves_discarded += 1

    def window_reset(self):
        """Count one restart of the window (frame size or encoding change)."""
        with self._lock:
            self.resets += 1

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
        with self._lock:
            figures = {'frames_in': self.frames_in, 'masks_out': self.masks_out,
                       'frames_dropped': sum(self.dropped.values()),
                       'solves': self.solves, 'solve_failures': self.solve_failures,
                       'solves_discarded': self.solves_discarded,
                       'window_resets': self.resets,
                       'mask_latency_p50_ms': 1e3 * p50, 'mask_latency_p95_ms': 1e3 * p95}
            figures.update({f'dropped_{k}': v for k, v in sorted(self.dropped.items())})
            figures.update({f'last_solve_{k}': v for k, v in self.last_solve.items()})
            if self.last_error:
                figures['last_solve_error'] = self.last_error
        return figures
