# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The benchmarks' one timing helper."""

import time

import numpy as np


def median_ms(function, repeats):
    """Return the median wall time of ``function()`` in milliseconds."""
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        times.append(time.perf_counter() - started)
    return 1000.0 * float(np.median(times))
