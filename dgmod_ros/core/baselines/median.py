# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The simplest honest baseline: the per-pixel temporal median of the window."""

import numpy as np

from ..window_data import check_window_data


class TemporalMedian:
    """
    Background = per-pixel median over the window's frames; foreground = the rest.

    ``L = median_t(D) 1^T``, ``S = D - L``. No parameters.
    """

    def fit(self, data, frame_shape, init=None):
        """Separate one window (``init`` is accepted for interface parity and unused)."""
        data = check_window_data(data, frame_shape)
        column = np.median(data, axis=1, keepdims=True)
        self.background_ = np.repeat(column, data.shape[1], axis=1)
        self.foreground_ = data - self.background_
        self.n_iter_ = 1
        self.info_ = 0
        return self
