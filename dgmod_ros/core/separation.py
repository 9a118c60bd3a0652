# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Separate one window channel by channel: the loop of every window method, stream and batch."""

from dataclasses import dataclass
import time

import numpy as np

from .linalg import c_order


@dataclass
class ChannelSeparation:
    """
    One window separated channel by channel.

    Attributes
    ----------
    backgrounds, foregrounds : list of ndarray (n, m) float32
        ``L`` and ``S`` of each channel.
    residuals : ndarray (C, n, m) float32
        ``D - L``, for the mask threshold.
    states : list
        Each channel's ``state_`` for a warm start (None where the method has none).
    iterations, info : int
        Largest ``n_iter_`` and ``info_`` over the channels (0 if not reported).
    diverged : bool
        True if a channel's ``info_`` is negative (a non-finite iterate).
    seconds : float
        Time of all the fits.

    """

    backgrounds: list
    foregrounds: list
    residuals: np.ndarray
    states: list
    iterations: int
    info: int
    diverged: bool
    seconds: float

    def threshold(self, mask_rule, data):
        """Return the mask threshold of this window (``data`` is the window, (C, n, m))."""
        return mask_rule.estimate_threshold(self.residuals, data)


def separate_channels(model, data, frame_shape, inits=None):
    """
    Fit ``model`` to each channel of a window.

    Parameters
    ----------
    model : estimator
        ``fit(data, frame_shape, init=None)`` setting ``background_`` and
        ``foreground_``, optionally ``state_``, ``n_iter_``, ``info_``.
    data : ndarray (C, n, m) float32
        The window, one (pixels x frames) matrix per channel.
    frame_shape : tuple (rows, cols)
        Size of one frame at the processing size.
    inits : list or None
        Each channel's warm start; None starts every channel cold.

    Returns
    -------
    ChannelSeparation

    """
    started = time.perf_counter()
    inits = inits if inits is not None else [None] * data.shape[0]
    backgrounds, foregrounds, states = [], [], []
    # In the window's own memory order (a frames-major window: F-ordered channels).
    residuals = np.empty_like(data, dtype=np.float32)
    iterations, info, diverged = 0, 0, False
    for channel, init in enumerate(inits):
        fitted = model.fit(data[channel], frame_shape, init=init)
        background = np.asarray(fitted.background_, dtype=np.float32)
        backgrounds.append(background)
        foregrounds.append(np.asarray(fitted.foreground_, dtype=np.float32))
        # The fused solver's L is F-ordered; D - L in one memory order.
        if not residuals[channel].flags.f_contiguous:
            background = c_order(background)
        np.subtract(data[channel], background, out=residuals[channel])
        states.append(getattr(fitted, 'state_', None))
        iterations = max(iterations, int(getattr(fitted, 'n_iter_', 0)))
        info = max(info, int(getattr(fitted, 'info_', 0)))
        diverged = diverged or getattr(fitted, 'info_', 0) < 0
    return ChannelSeparation(backgrounds=backgrounds, foregrounds=foregrounds,
                             residuals=residuals, states=states,
                             iterations=iterations, info=info, diverged=diverged,
                             seconds=time.perf_counter() - started)
