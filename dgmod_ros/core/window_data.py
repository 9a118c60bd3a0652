# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The one check of a window's data that every window method runs before fitting."""

import numpy as np


def check_window_data(data, frame_shape):
    """
    Return a window (n pixels x m frames) as float32 after checking it.

    Raises
    ------
    ValueError
        When ``data`` is not 2-D, holds fewer than 2 frames, does not match
        ``frame_shape`` (rows, cols) or contains NaN or Inf.

    """
    data = np.asarray(data)
    if data.ndim != 2:
        raise ValueError(f'data must be 2-D (pixels x frames), got shape {data.shape}')
    n, m = data.shape
    if m < 2:
        raise ValueError(f'data must hold at least 2 frames (columns), got {m}')
    if len(frame_shape) != 2 or frame_shape[0] * frame_shape[1] != n:
        raise ValueError(f'frame_shape {tuple(frame_shape)} does not match {n} pixels')
    data = np.asarray(data, dtype=np.float32)
    if not np.all(np.isfinite(data)):
        raise ValueError('data contains NaN or Inf')
    return data
