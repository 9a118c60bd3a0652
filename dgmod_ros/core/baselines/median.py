# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The simplest honest baseline: the per-pixel temporal median of the window."""

import numpy as np


class TemporalMedian:
    """
    Background = per-pixel median over the window's frames; foreground = the rest.

    ``L = median_t(D) 1^T``, ``S = D - L``. No parameters.
    """

    def fit(self, data, frame_shape, init=None):
        """Separate one window (``init`` is accepted for interface parity and unused)."""
        data = np.asarray(data, dtype=np.float32)
        if data.ndim != 2 or data.shape[0] != frame_shape[0] * frame_shape[1]:
            raise ValueError(f'data of shape {data.shape} does not match frame_shape '
                             f'{tuple(frame_shape)}')
        column = np.median(data, axis=1, keepdims=True)
        self.background_ = np.repeat(column, data.shape[1], axis=1)
        self.foreground_ = data - self.background_
        self.n_iter_ = 1
        self.info_ = 0
        return self
