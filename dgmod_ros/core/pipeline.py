# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Offline separation of a whole sequence: batch tiling and the streaming loop."""

from dataclasses import dataclass

import numpy as np

from .masks import MaskRule
from .preprocess import frame_columns
from .separation import separate_channels


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
                   channel_order='rgb', value_range=None, processing_pixels=None):
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
    processing_pixels : int or None
        Largest processing size (pixels) after ``scale``; None: no limit.

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
    for start, stop, first_new in window_tiles(len(frames), int(window)):
        columns = []
        for frame in frames[start:stop]:
            if np.asarray(frame).shape[:2] != input_shape:
                raise ValueError(f'frame size changed from {input_shape} to '
                                 f'{np.asarray(frame).shape[:2]}')
            frame_data, shape = frame_columns(frame, scale, color, channel_order, value_range,
                                              processing_pixels)
            columns.append(frame_data)
        data = np.stack(columns, axis=2)                            # (C, n, m)
        rows, cols = shape[:2]
        separated = separate_channels(model, data, (rows, cols))
        record = SolveRecord(first=start, last=stop - 1, iterations=separated.iterations,
                             seconds=separated.seconds)
        magnitude = np.max([np.abs(s) for s in separated.foregrounds], axis=0)
        threshold = separated.threshold(rule, data)
        mean_background = np.stack([b.mean(axis=1) for b in separated.backgrounds],
                                   axis=1).reshape(rows, cols, -1)
        for index in range(first_new, stop):
            mask = rule.apply(magnitude[:, index - start].reshape(rows, cols), threshold,
                              input_shape)
            first = index == first_new
            yield (index, mask, mean_background if first else None, record if first else None)
