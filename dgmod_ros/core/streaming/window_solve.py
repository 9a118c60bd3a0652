# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""One window solve: a :class:`~.results.WindowSnapshot` in, a background model out."""

from dataclasses import replace
import time

import cv2
import numpy as np

from .fast_path import background_basis, projection_residual, sampled_basis
from .noise_levels import known_levels, pixel_noise
from .photometric import chroma_noise
from .results import BackgroundModel, SolverFailure
from .solve_resolution import carry_backgrounds, downsample_window, PixelSample
from ..separation import separate_channels


def _solved_shape(solve):
    """Return the (rows, cols, C) a snapshot or model is solved at (None: its own shape)."""
    return tuple(solve.solve_shape or solve.shape)


def warm_starts(snapshot):
    """
    Return each channel's warm start for the snapshot's solve (None: cold).

    The previous solve's states, shifted by the frames the window moved on,
    when the snapshot asks for a warm start (``warm_start``) and the previous
    window has the same shape, solve shape and length and still overlaps.
    """
    channels = snapshot.shape[2]
    previous = snapshot.previous
    if (not snapshot.warm_start or previous is None or previous.shape != snapshot.shape
            or _solved_shape(previous) != _solved_shape(snapshot) or not previous.states
            or any(s is None for s in previous.states)):
        return [None] * channels
    if snapshot.first_column is not None and previous.first_column is not None:
        shift = snapshot.first_column - previous.first_column
    else:
        shift = snapshot.first_id - previous.first_id
    width = snapshot.width
    if not 0 <= shift < width or previous.states[0].frames != width:
        return [None] * channels
    return [state.shifted(shift) for state in previous.states]


def healed_starts(starts, data, healed, shape, small_shape):
    """
    Return the warm starts with the pixels of ``healed`` started from the data itself.

    Where the window took the frame in every column
    (:meth:`~.background_memory.BackgroundMemory.overwrite`), the previous
    solve's iterates hold what has left; a few warm sweeps would carry them
    on, and the refit holds out the entries the solve calls foreground. There
    the start is ``L = U = D`` with no foreground, noise or duals. A healed
    pixel covers every solved pixel its area overlaps.
    """
    if healed is None or not healed.any() or all(s is None for s in starts):
        return starts
    rows, cols = shape[:2]
    area = healed.reshape(rows, cols).astype(np.float32)
    if tuple(small_shape[:2]) != (rows, cols):
        area = cv2.resize(area, (small_shape[1], small_shape[0]), interpolation=cv2.INTER_AREA)
    pixels = np.flatnonzero(area > 0)
    healed_states = []
    for channel, state in enumerate(starts):
        if state is None:
            healed_states.append(None)
            continue
        arrays = {}
        for name in ('background', 'low_rank', 'foreground', 'noise', 'dual_low_rank',
                     'dual_noise'):
            array = getattr(state, name).copy()
            array[pixels] = data[channel][pixels] if name in ('background', 'low_rank') else 0
            arrays[name] = array
        healed_states.append(replace(state, **arrays))
    return healed_states


def _sampled(sample, array):
    """Return ``array`` (..., n, m) at ``sample``'s pixels; as it is without a sample or array."""
    return array if sample is None or array is None else sample.take(array)


def previous_known(snapshot):
    """Return the previous solve's known levels (n,) when it has the snapshot's shape, or None."""
    previous = snapshot.previous
    if (previous is None or previous.known_noise is None
            or tuple(previous.shape) != tuple(snapshot.shape)):
        return None
    return previous.known_noise


def window_noise(snapshot, residuals, basis, observed, sample=None, known=None):
    """
    Return each pixel's noise level from the residual ``snapshot.noise_source`` names.

    'solve': the solve's ``D - L``; 'projection' / 'least_squares': each
    column against its robust / least-squares projection on the fast path's
    basis (the statistic the per-frame decision thresholds); 'max': the
    larger of the 'solve' and 'projection' levels. With a
    :class:`~.solve_resolution.PixelSample`, the levels are read at its
    pixels (``residuals`` and ``observed``, the snapshot's observed entries,
    hold those only, and ``known``, the previous solve's known levels, if
    any) and upsampled.
    """
    uniform = snapshot.decision == 'uniform'
    source = snapshot.noise_source

    def level(residual):
        return pixel_noise(residual, snapshot.shape, observed, uniform=uniform, sample=sample,
                           doubtful_floor=snapshot.doubtful_floor, offset_k=snapshot.offset_k,
                           known=known)

    if source == 'solve':
        return level(residuals)
    projected = level(_sampled(sample, projection_residual(
        basis, snapshot.window(), robust=source != 'least_squares')))
    return np.maximum(projected, level(residuals)) if source == 'max' else projected


def solve_window(snapshot):
    """
    Separate a snapshot with its own estimator; read nothing else.

    A snapshot whose ``solve_shape`` is smaller than its frames is solved at
    that size and its full-size background carried from the solve
    (:mod:`~dgmod_ros.core.streaming.solve_resolution`); with
    ``refit_background`` the background is that fit at any solve size (each
    pixel's own series on the solve's leading temporal factors, the entries
    the solve called foreground held out). The basis is computed at the
    frames' size either way; the noise levels of a downscaled solve are read
    at one full-size pixel per solved one and upsampled
    (:class:`~.solve_resolution.PixelSample`).

    Raises
    ------
    SolverFailure
        When the estimator raises or returns non-finite values.

    """
    rows, cols, channels = snapshot.shape
    # The columns each downscaled and sampled once (ColumnCache), when the
    # snapshot holds buffered columns and their cache.
    columns, cache = snapshot.data, snapshot.column_cache
    if isinstance(columns, np.ndarray) or cache is None:
        columns = cache = None
    else:
        cache.keep(columns)
    # The columns are stacked (in the solve's thread) only where a step reads
    # the whole window: with the cache, the solve and its levels do not.
    window = snapshot.window
    small_shape = _solved_shape(snapshot)
    downscaled = small_shape != tuple(snapshot.shape)
    carried = downscaled or snapshot.refit_background
    started = time.perf_counter()
    if not downscaled:
        data = window()
    elif cache is None:
        data = downsample_window(window(), snapshot.shape, small_shape)
    else:
        data = cache.small_window(columns, snapshot.shape, small_shape)
    try:
        starts = healed_starts(warm_starts(snapshot), data, snapshot.healed, snapshot.shape,
                               small_shape)
        separated = separate_channels(snapshot.model, data, small_shape[:2], starts)
    except (ValueError, FloatingPointError, np.linalg.LinAlgError) as error:
        raise SolverFailure(f'window solve failed: {error}') from error
    backgrounds, residuals = separated.backgrounds, separated.residuals
    if separated.diverged or not all(np.all(np.isfinite(b)) for b in backgrounds):
        raise SolverFailure('window solve produced non-finite values')
    rank = int(snapshot.basis_rank)
    if carried:
        # Factors only: the full-size backgrounds are never formed whole.
        carry = carry_backgrounds(snapshot.frames(), snapshot.shape, backgrounds, residuals,
                                  small_shape, rank)
        bases, newest, mean = carry.bases(rank), carry.newest(), carry.mean()
    else:
        bases = [background_basis(b, rank) for b in backgrounds]
        newest = np.stack([b[:, -1] for b in backgrounds], axis=1)
        mean = np.stack([b.mean(axis=1) for b in backgrounds], axis=1)
    # The frames are in [0, 1], and so is the image a planner reads: the
    # refit of a pixel the window saw in few frames extrapolates where its
    # newest frames were held out (docs/results.md).
    newest, mean = np.clip(newest, 0, 1), np.clip(mean, 0, 1)
    basis = np.zeros((channels, rows * cols, max(b.shape[1] for b in bases)), dtype=np.float32)
    for channel, channel_basis in enumerate(bases):
        basis[channel, :, :channel_basis.shape[1]] = channel_basis
    noise = chroma = threshold = known = None
    if snapshot.decision != 'global':
        # A downscaled solve reads its levels at one full-size pixel per
        # solved one, and needs its residual there only.
        sample = PixelSample(snapshot.shape, small_shape) if downscaled else None
        if sample is not None and cache is not None:
            sampled = cache.sampled_window(columns, sample)
        else:
            sampled = _sampled(sample, window())
        observed = _sampled(sample, snapshot.observed)
        if carried:
            residuals = carry.residuals(sampled, None if sample is None else sample.pixels)
        known = previous_known(snapshot)
        noise = window_noise(snapshot, residuals, basis, observed, sample,
                             known if known is None or sample is None else known[sample.pixels])
        if not snapshot.holds_fill:
            # A window that still holds its fill may hold a person in view from the start.
            known = known_levels(noise, observed, known, sample)
        if channels == 3:
            chroma = chroma_noise(sampled, residuals, snapshot.shape, observed,
                                  snapshot.decision == 'uniform', sample)
    else:
        # The global rule's threshold costs a median over the whole window; the
        # per-pixel decisions read ``noise`` instead.
        if carried:
            residuals = carry.residuals(window())
        threshold = snapshot.mask_rule.estimate_threshold(residuals, window())
    return BackgroundModel(
        basis=basis, background=newest.reshape(rows, cols, channels),
        mean_background=mean.reshape(rows, cols, channels), threshold=threshold,
        shape=snapshot.shape, first_id=snapshot.first_id, last_id=snapshot.last_id,
        states=separated.states, seconds=time.perf_counter() - started,
        iterations=separated.iterations, info=separated.info, ticket=snapshot.ticket,
        noise=noise, first_column=snapshot.first_column, chroma_noise=chroma, known_noise=known,
        solve_shape=small_shape, fit_basis=sampled_basis(basis))
