# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Cost of one window solve of a 640 x 480 camera: the defaults, ``scale:=1.0`` capped and uncapped.

Builds each case's window from the same synthetic 640 x 480 colour scene at
its processing size (the defaults: 184 x 138 by ``processing_pixels``,
solved at 92 x 69 and refit; ``scale`` 0.5 without that cap, the defaults
before 2026-12-04: 320 x 240, solved at 160 x 120 and refit; the defaults
before 2026-12-01: 320 x 240 solved as it is, no refit;
``scale=1.0``: 640 x 480, solved at ``solve_pixels`` and carried back;
``scale=1.0`` uncapped: solved at 640 x 480; the defaults with 5 sweeps
per solve, the count before 2026-12-01), solves it once cold, then
times the warm-started solve of the window one frame on, the cases
interleaved so that the machine's load falls on all alike. Each snapshot
holds the buffered columns, as the detector hands them over, so that the
stacking in the solve's thread is timed too. Prints the median
ms per solve, the ratios to the defaults, and where a capped solve's time
goes (the carry, the noise levels). Asserts nothing.

Usage::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/bench_capped_solve.py
        [--repeats 3] [--threads 1]
"""

import argparse
import contextlib
from dataclasses import replace
import time

from dgmod_ros import config
from dgmod_ros.core.numba_setup import use_threads
from dgmod_ros.core.preprocess import frame_columns
from dgmod_ros.core.streaming import solve_resolution, window_solve
from dgmod_ros.core.streaming.results import WindowSnapshot
from dgmod_ros.core.streaming.solve_resolution import solve_shape
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np

# Every case but the defaults lifts processing_pixels: they are the sizes compared before it.
_UNCAPPED = {'processing_pixels': 640 * 480}
CASES = (('defaults (184 x 138)', {}),
         ('scale=1.0, capped', {'scale': 1.0, **_UNCAPPED}),
         ('defaults before', {'solve_scale': 1.0, 'refit_background': False,
                              'solve_pixels': 320 * 240, **_UNCAPPED}),
         ('scale=1.0, uncapped', {'scale': 1.0, 'solve_scale': 1.0,
                                  'solve_pixels': 640 * 480, **_UNCAPPED}),
         ('scale 0.5 without processing_pixels', dict(_UNCAPPED)),
         ('defaults, 5 sweeps', {'stream_max_iter': 5}))
# The case whose stages are timed: the capped full-resolution solve.
TIMED = 1


def snapshots(values, frames):
    """Return the case's window and the window one frame on, warm-started from the first."""
    detector = config.build_detector(dict(config.DEFAULTS, **values))
    width = int(detector.window)
    detector.validate()._build_helpers()             # the estimator and the mask rule
    converted = [frame_columns(f, detector.scale, detector.color, 'rgb', None,
                               int(detector.processing_pixels))
                 for f in frames[:width + 1]]
    columns, shape = [c for c, _ in converted], converted[0][1]

    def snapshot(first, previous):
        # The buffered columns, as the detector hands them over (stacked in the solve).
        data = tuple(columns[first:first + width])
        return WindowSnapshot(
            data=data, shape=shape, first_id=first, last_id=first + width - 1,
            previous=previous, model=detector.model_, mask_rule=detector.mask_rule_,
            basis_rank=int(detector.basis_rank), decision=detector.decision,
            noise_source=detector.noise_source,
            solve_shape=solve_shape(shape, int(detector.solve_pixels),
                                    float(detector.solve_scale)),
            refit_background=bool(detector.refit_background))

    first = window_solve.solve_window(snapshot(0, None))
    return snapshot(1, first)


class StageClock:
    """Add up the wall time of named module functions while installed."""

    def __init__(self, targets):
        self.targets = targets
        self.seconds = {name: 0.0 for _, name in targets}   # a name twice: one sum
        self.saved = []

    def __enter__(self):
        for module, name in self.targets:
            function = getattr(module, name, None)
            if function is None:                   # an earlier form of the code: not timed
                continue
            self.saved.append((module, name, function))

            def timed(*args, _function=function, _name=name, **kwargs):
                started = time.perf_counter()
                try:
                    return _function(*args, **kwargs)
                finally:
                    self.seconds[_name] += time.perf_counter() - started
            setattr(module, name, timed)
        return self

    def __exit__(self, *exc):
        for module, name, function in self.saved:
            setattr(module, name, function)


def main():
    """Time each case's warm-started solve, interleaved; print ms and ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--repeats', type=int, default=3)
    parser.add_argument('--threads', type=int, default=0,
                        help="the kernels' threads (the node and stream mode run "
                             "solve_threads, 1); 0: numba's default, every core")
    args = parser.parse_args()
    use_threads(args.threads)
    frames = list(synthetic_scene(n_frames=40, shape=(480, 640), seed=3).frames)
    windows = [snapshots(values, frames) for _, values in CASES]
    times = [[] for _ in CASES]
    stages = [
        (window_solve, 'separate_channels'), (window_solve, 'downsample_window'),
        (window_solve, 'carry_backgrounds'), (window_solve, 'background_basis'),
        (solve_resolution, 'background_basis'),
        (window_solve, 'window_noise'), (window_solve, 'chroma_noise'),
    ]
    clock = StageClock(stages)
    for _ in range(args.repeats):
        for case, snapshot in enumerate(windows):
            with clock if case == TIMED else contextlib.nullcontext():
                started = time.perf_counter()
                window_solve.solve_window(replace(snapshot))    # its columns unstacked
                times[case].append(time.perf_counter() - started)
    base = float(np.median(times[0]))
    print(f'one window solve of a 640 x 480 camera, window {len(windows[0].data)} '
          f'frames x 3 channels, warm start, median of {args.repeats}')
    for (name, _), case_times, snapshot in zip(CASES, times, windows):
        ms = 1000.0 * float(np.median(case_times))
        rows, cols, _ = snapshot.shape
        small = snapshot.solve_shape
        print(f'  {name:22s} {cols} x {rows} solved at {small[1]} x {small[0]}: '
              f'{ms:8.1f} ms per solve  {ms / (1000.0 * base):5.2f}x the defaults')
    capped = float(np.sum(times[TIMED]))
    print('  where the capped solve goes (share of its time):')
    for name, seconds in clock.seconds.items():
        print(f'    {name:22s} {1000.0 * seconds / args.repeats:8.1f} ms  '
              f'{seconds / capped:6.1%}')


if __name__ == '__main__':
    main()
