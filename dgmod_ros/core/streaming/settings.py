# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Parameter checks of the streaming detectors and their all-or-nothing reconfiguration."""

import inspect

import numpy as np

from ..masks import MaskRule

# Residuals the per-pixel noise level may come from (see window_solve.window_noise).
NOISE_SOURCES = ('solve', 'projection', 'least_squares', 'max')


def _require_scale(name, value):
    """Raise ``ValueError`` unless ``value`` is a number in (0, 1]."""
    if not (isinstance(value, (int, float)) and 0 < value <= 1):
        raise ValueError(f'{name} must be in (0, 1], got {value!r}')


def check_scale_and_color(scale, color):
    """Raise ``ValueError`` for a processing scale outside (0, 1] or an unknown colour mode."""
    _require_scale('scale', scale)
    if color not in ('gray', 'rgb'):
        raise ValueError(f"color must be 'gray' or 'rgb', got {color!r}")


def _require_integer(name, value, low, high=None, high_label=None):
    """Raise ``ValueError`` unless ``value`` is an integer in ``[low, high]`` (None: no bound)."""
    if int(value) == value and low <= value and (high is None or value <= high):
        return
    if high is None:
        raise ValueError(f'{name} must be an integer >= {low}, got {value!r}')
    raise ValueError(f'{name} must be an integer in [{low}, {high_label or high}], '
                     f'got {value!r}')


def _require_non_negative(name, value):
    """Raise ``ValueError`` unless ``value`` is a finite number >= 0."""
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f'{name} must be >= 0, got {value!r}')


def check_window_parameters(detector):
    """Raise ``ValueError`` naming the first bad parameter of a sliding-window detector."""
    window, stride = detector.window, detector.stride
    _require_integer('window', window, 2)
    _require_integer('stride', stride, 1, window, f'window={window}')
    check_scale_and_color(detector.scale, detector.color)
    _require_non_negative('motion_threshold', detector.motion_threshold)
    _require_integer('min_frames', detector.min_frames, 2, window, f'window={window}')
    if not 0 < detector.global_change_fraction <= 1:
        raise ValueError(f'global_change_fraction must be in (0, 1], got '
                         f'{detector.global_change_fraction!r}')
    _require_integer('basis_rank', detector.basis_rank, 1)
    _require_integer('memory_spacing', detector.memory_spacing, 1)
    _require_integer('absorb_frames', detector.absorb_frames, 1)
    if detector.decision not in ('adaptive', 'uniform', 'global'):
        raise ValueError(f"decision must be 'adaptive', 'uniform' or 'global', "
                         f'got {detector.decision!r}')
    if detector.noise_source not in NOISE_SOURCES:
        raise ValueError(f'noise_source must be one of {NOISE_SOURCES}, '
                         f'got {detector.noise_source!r}')
    if not (np.isfinite(detector.pixel_k) and detector.pixel_k > 0):
        raise ValueError(f'pixel_k must be positive, got {detector.pixel_k!r}')
    size = detector.median_size
    if int(size) != size or size < 1 or size % 2 == 0:
        raise ValueError(f'median_size must be an odd positive integer, got {size!r}')
    _require_integer('still_frames', detector.still_frames, 0)
    _require_non_negative('mrf_beta', detector.mrf_beta)
    _require_integer('texture_bits', detector.texture_bits, 0, 48)
    _require_non_negative('moving_texture_k', detector.moving_texture_k)
    _require_integer('moving_texture_bits', detector.moving_texture_bits, 0, 48)
    _require_integer('solve_lag', detector.solve_lag, 0)
    _require_integer('solve_pixels', detector.solve_pixels, 1)
    _require_scale('solve_scale', detector.solve_scale)
    (detector.mask_rule or MaskRule()).validate()


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
