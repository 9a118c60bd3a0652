# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The streaming detectors' parameter constraints and their all-or-nothing reconfiguration."""

import inspect
from numbers import Integral, Real

from ..validation import (Interval, NON_NEGATIVE, NON_NEGATIVE_INTEGER, Options, POSITIVE,
                          POSITIVE_INTEGER)

# Residuals the per-pixel noise level may come from (see window_solve.window_noise).
NOISE_SOURCES = ('solve', 'projection', 'least_squares', 'max')

#: The processing scale and the colour mode, shared by every streaming detector.
SCALE = (Interval(Real, 0, 1, closed='right'),)
COLOR = (Options('gray', 'rgb'),)
#: LBSP Hamming distances: 16 bits a channel, three channels at most.
TEXTURE_BITS = (Interval(Integral, 0, 48),)

#: :class:`~dgmod_ros.core.streaming.sliding_window.SlidingWindowDetector`'s
#: constraints (:mod:`~dgmod_ros.core.validation`), in the order they are checked.
WINDOW_CONSTRAINTS = {
    'window': [Interval(Integral, 2, None)],
    'stride': [Interval(Integral, 1, 'window')],
    'scale': SCALE,
    'processing_pixels': POSITIVE_INTEGER,
    'color': COLOR,
    'motion_threshold': NON_NEGATIVE,
    'min_frames': [Interval(Integral, 2, 'window')],
    'global_change_fraction': [Interval(Real, 0, 1, closed='right')],
    'basis_rank': POSITIVE_INTEGER,
    'memory_spacing': POSITIVE_INTEGER,
    'memory_columns': [Interval(Integral, 2, None)],
    'absorb_frames': POSITIVE_INTEGER,
    'decision': [Options('adaptive', 'uniform', 'global')],
    'noise_source': [Options(*NOISE_SOURCES)],
    'doubtful_floor': [Interval(Real, 0, 1, closed='both')],
    'pixel_k': POSITIVE,
    'median_size': [Interval(Integral, 1, None, odd=True)],
    'still_frames': NON_NEGATIVE_INTEGER,
    'line_pixels': NON_NEGATIVE_INTEGER,
    'mrf_beta': NON_NEGATIVE,
    'texture_bits': TEXTURE_BITS,
    'moving_texture_k': NON_NEGATIVE,
    'moving_texture_bits': TEXTURE_BITS,
    'solve_lag': NON_NEGATIVE_INTEGER,
    'solve_pixels': POSITIVE_INTEGER,
    'solve_scale': SCALE,
}


def assign_validated(target, params):
    """
    Set constructor parameters on ``target`` and run its ``validate()``; undo all on ValueError.

    Names that are not parameters of ``type(target)``'s constructor are refused
    before anything changes. Returns the previous values of the parameters set.
    """
    unknown = set(params) - set(inspect.signature(type(target)).parameters)
    if unknown:
        raise ValueError(f'unknown parameters: {", ".join(sorted(unknown))}')
    old = {name: getattr(target, name) for name in params}
    for name, value in params.items():
        setattr(target, name, value)
    try:
        target.validate()
    except ValueError:
        for name, value in old.items():
            setattr(target, name, value)
        raise
    return old
