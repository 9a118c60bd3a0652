# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Offline separation of a whole sequence: batch tiling and the streaming loop."""

from dataclasses import dataclass
import time

import numpy as np

from .masks import MaskRule
from .preprocess import processing_shape, resize, to_float_channels


@dataclass
class SolveRecord:
    """Cost of one window solve, for reports."""

    first: int
    last: int
    seconds: float
    iterations: int


def window_tiles(count, window):
    """
    Split ``count`` frames into consecutive windows of ``window`` frames.

    The last window is the last ``window`` frames (it overlaps the previous
    one when ``count`` is not a multiple), so every window has full length.
    Returns (start, stop, first_new) triples: frames ``first_new:stop`` take
    their masks from that window.
    """
    if count <= 0:
        return []
    window = min(window, count)
    tiles = []
    start = 0
    while start < count:
        stop = min(start + window, count)
        tiles.append((stop - window, stop, start))
        start = stop
    return tiles


def batch_separate(frames, model, window=60, scale=0.5, color='gray', mask_rule=None,
                   channel_order='rgb', value_range=None):
    """
    Separate a sequence window by window, each frame masked by its whole window.

    Parameters
    ----------
    frames : sequence of ndarray
        Frames of one size, (h, w) or (h, w, 3|4).
    model : estimator
        Object with ``fit(data, frame_shape)`` setting ``background_`` and
        ``foreground_`` (n x m); optionally ``n_iter_``.
    window : int, default=60
        Frames per solve.
    scale : float, default=0.5
        Processing scale; masks are returned at the input size.
    color : {'gray', 'rgb'}, default='gray'
        'rgb' solves each channel and fuses by the largest magnitude.
    mask_rule : MaskRule or None
        None: ``MaskRule()``.
    channel_order : {'rgb', 'bgr'}, default='rgb'
        Channel order of colour frames.
    value_range : float or None
        Full-scale pixel value; None uses the dtype's.

    Yields
    ------
    index : int
        Frame index.
    mask : ndarray uint8 (h, w)
        0 or 255.
    background : ndarray float32 (rows, cols, C) or None
        The window's mean background, given with the first frame of each window.
    record : SolveRecord or None
        The cost of the window solve, given with the first frame of each window.

    """
    rule = (mask_rule or MaskRule()).validate()
    frames = list(frames)
    if not frames:
        return
    input_shape = np.asarray(frames[0]).shape[:2]
    rows, cols = processing_shape(input_shape, scale)
    for start, stop, first_new in window_tiles(len(frames), int(window)):
        stack = []
        for frame in frames[start:stop]:
            if np.asarray(frame).shape[:2] != input_shape:
                raise ValueError(f'frame size changed from {input_shape} to '
                                 f'{np.asarray(frame).shape[:2]}')
            channels = to_float_channels(frame, channel_order, color, value_range)
            stack.append(resize(channels, (rows, cols)).reshape(rows * cols, -1))
        data = np.stack(stack, axis=2)                              # (n, C, m)
        started = time.perf_counter()
        magnitudes, backgrounds, residuals, iterations = [], [], [], 0
        for channel in range(data.shape[1]):
            fitted = model.fit(np.ascontiguousarray(data[:, channel, :]), (rows, cols))
            magnitudes.append(np.abs(np.asarray(fitted.foreground_, dtype=np.float32)))
            background = np.asarray(fitted.background_, dtype=np.float32)
            backgrounds.append(background.mean(axis=1))
            residuals.append(data[:, channel, :] - background)
            iterations = max(iterations, int(getattr(fitted, 'n_iter_', 0)))
        record = SolveRecord(first=start, last=stop - 1, iterations=iterations,
                             seconds=time.perf_counter() - started)
        magnitude = np.max(magnitudes, axis=0)
        threshold = rule.estimate_threshold(np.stack(residuals), np.moveaxis(data, 1, 0))
        mean_background = np.stack(backgrounds, axis=1).reshape(rows, cols, -1)
        for index in range(first_new, stop):
            mask = rule.apply(magnitude[:, index - start].reshape(rows, cols), threshold,
                              input_shape)
            first = index == first_new
            yield (index, mask, mean_background if first else None, record if first else None)
