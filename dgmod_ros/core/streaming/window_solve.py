# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""One window solve: a :class:`~.results.WindowSnapshot` in, a background model out."""

import time

import numpy as np

from .fast_path import background_basis
from .foreground import pixel_noise
from .results import BackgroundModel, SolverFailure


def warm_starts(snapshot):
    """
    Return each channel's warm start for the snapshot's solve (None: cold).

    The previous solve's states, shifted by the frames the window moved on,
    when the previous window has the same shape and length and still overlaps.
    """
    channels = snapshot.shape[2]
    previous = snapshot.previous
    if (previous is None or previous.shape != snapshot.shape or not previous.states
            or any(s is None for s in previous.states)):
        return [None] * channels
    if snapshot.first_column is not None and previous.first_column is not None:
        shift = snapshot.first_column - previous.first_column
    else:
        shift = snapshot.first_id - previous.first_id
    width = snapshot.data.shape[2]
    if not 0 <= shift < width or previous.states[0].frames != width:
        return [None] * channels
    return [state.shifted(shift) for state in previous.states]


def solve_window(snapshot):
    """
    Separate a snapshot with its own estimator; read nothing else.

    Raises
    ------
    SolverFailure
        When the estimator raises or returns non-finite values.

    """
    rows, cols, channels = snapshot.shape
    started = time.perf_counter()
    bases, backgrounds, means, residuals, states = [], [], [], [], []
    iterations, info = 0, 0
    for channel, init in enumerate(warm_starts(snapshot)):
        data = snapshot.data[channel]
        try:
            fitted = snapshot.model.fit(data, (rows, cols), init=init)
        except (ValueError, FloatingPointError, np.linalg.LinAlgError) as error:
            raise SolverFailure(f'window solve failed: {error}') from error
        background = np.asarray(fitted.background_, dtype=np.float32)
        if not np.all(np.isfinite(background)) or getattr(fitted, 'info_', 0) < 0:
            raise SolverFailure('window solve produced non-finite values')
        bases.append(background_basis(background, int(snapshot.basis_rank)))
        backgrounds.append(background[:, -1])
        means.append(background.mean(axis=1))
        residuals.append(data - background)
        states.append(getattr(fitted, 'state_', None))
        iterations = max(iterations, int(getattr(fitted, 'n_iter_', 0)))
        info = max(info, int(getattr(fitted, 'info_', 0)))
    residuals = np.stack(residuals)
    noise = None
    if snapshot.decision != 'global':
        noise = pixel_noise(residuals, snapshot.shape, snapshot.observed,
                            uniform=snapshot.decision == 'uniform')
    rank = max(b.shape[1] for b in bases)
    basis = np.zeros((channels, rows * cols, rank), dtype=np.float32)
    for channel, channel_basis in enumerate(bases):
        basis[channel, :, :channel_basis.shape[1]] = channel_basis
    return BackgroundModel(
        basis=basis,
        background=np.stack(backgrounds, axis=1).reshape(rows, cols, channels),
        mean_background=np.stack(means, axis=1).reshape(rows, cols, channels),
        threshold=snapshot.mask_rule.estimate_threshold(residuals, snapshot.data),
        shape=snapshot.shape, first_id=snapshot.first_id, last_id=snapshot.last_id,
        states=states, seconds=time.perf_counter() - started,
        iterations=iterations, info=info, ticket=snapshot.ticket, noise=noise,
        first_column=snapshot.first_column)
