# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Parameter checks of the streaming detectors and their all-or-nothing reconfiguration."""

import inspect

import numpy as np

from ..masks import MaskRule

# Residuals the per-pixel noise level may come from (see window_solve.window_noise).
NOISE_SOURCES = ('solve', 'projection', 'least_squares', 'max')


def check_scale_and_color(scale, color):
    """Raise ``ValueError`` for a processing scale outside (0, 1] or an unknown colour mode."""
    if not (isinstance(scale, (int, float)) and 0 < scale <= 1):
        raise ValueError(f'scale must be in (0, 1], got {scale!r}')
    if color not in ('gray', 'rgb'):
        raise ValueError(f"color must be 'gray' or 'rgb', got {color!r}")


def check_window_parameters(detector):
    """Raise ``ValueError`` naming the first bad parameter of a sliding-window detector."""
    window, stride = detector.window, detector.stride
    if int(window) != window or window < 2:
        raise ValueError(f'window must be an integer >= 2, got {window!r}')
    if int(stride) != stride or not 1 <= stride <= window:
        raise ValueError(f'stride must be an integer in [1, window={window}], got {stride!r}')
    check_scale_and_color(detector.scale, detector.color)
    if not (np.isfinite(detector.motion_threshold) and detector.motion_threshold >= 0):
        raise ValueError(f'motion_threshold must be >= 0, got {detector.motion_threshold!r}')
    min_frames = detector.min_frames
    if int(min_frames) != min_frames or not 2 <= min_frames <= window:
        raise ValueError(f'min_frames must be an integer in [2, window={window}], '
                         f'got {min_frames!r}')
    if not 0 < detector.global_change_fraction <= 1:
        raise ValueError(f'global_change_fraction must be in (0, 1], got '
                         f'{detector.global_change_fraction!r}')
    rank = detector.basis_rank
    if int(rank) != rank or rank < 1:
        raise ValueError(f'basis_rank must be a positive integer, got {rank!r}')
    spacing = detector.memory_spacing
    if int(spacing) != spacing or spacing < 1:
        raise ValueError(f'memory_spacing must be a positive integer, got {spacing!r}')
    absorb = detector.absorb_frames
    if int(absorb) != absorb or absorb < 1:
        raise ValueError(f'absorb_frames must be a positive integer, got {absorb!r}')
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
    still = detector.still_frames
    if int(still) != still or still < 0:
        raise ValueError(f'still_frames must be an integer >= 0, got {still!r}')
    if not (np.isfinite(detector.mrf_beta) and detector.mrf_beta >= 0):
        raise ValueError(f'mrf_beta must be >= 0, got {detector.mrf_beta!r}')
    bits = detector.texture_bits
    if int(bits) != bits or not 0 <= bits <= 48:
        raise ValueError(f'texture_bits must be an integer in [0, 48], got {bits!r}')
    if not (np.isfinite(detector.moving_texture_k) and detector.moving_texture_k >= 0):
        raise ValueError(f'moving_texture_k must be >= 0, got {detector.moving_texture_k!r}')
    bits = detector.moving_texture_bits
    if int(bits) != bits or not 0 <= bits <= 48:
        raise ValueError(f'moving_texture_bits must be an integer in [0, 48], got {bits!r}')
    lag = detector.solve_lag
    if int(lag) != lag or not 0 <= lag <= stride:
        raise ValueError(f'solve_lag must be an integer in [0, stride={stride}], got {lag!r}')
    pixels = detector.solve_pixels
    if int(pixels) != pixels or pixels < 1:
        raise ValueError(f'solve_pixels must be a positive integer, got {pixels!r}')
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
