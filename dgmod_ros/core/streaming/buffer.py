# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The buffered frames of a sliding window, and the scene-change rule that restarts it."""

from collections import deque

import numpy as np

from ..preprocess import moving_frames, resize


class FrameWindow:
    """
    The newest ``capacity`` frames as per-channel columns, with their sequence numbers.

    Parameters
    ----------
    capacity : int
        Frames kept; older ones fall out as new ones arrive.

    """

    def __init__(self, capacity):
        self._frames = deque(maxlen=int(capacity))
        self._ids = deque(maxlen=int(capacity))

    @property
    def capacity(self):
        """Return how many frames the window keeps."""
        return self._frames.maxlen

    def __len__(self):
        return len(self._frames)

    @property
    def first_id(self):
        """Return the sequence number of the oldest buffered frame."""
        return self._ids[0]

    @property
    def last_id(self):
        """Return the sequence number of the newest buffered frame."""
        return self._ids[-1]

    def append(self, columns, frame_id):
        """Buffer one frame's columns (C, n)."""
        self._frames.append(columns)
        self._ids.append(frame_id)

    def is_motionless(self, columns, threshold):
        """Tell whether ``columns`` differs from the newest frame by less than ``threshold``."""
        if threshold <= 0 or not self._frames:
            return False
        pair = np.stack([self._frames[-1].ravel(), columns.ravel()], axis=1)
        return moving_frames(pair, threshold).size != 2

    def columns(self):
        """Return the buffered frames (C, n) oldest first, as a tuple (they are never written)."""
        return tuple(self._frames)

    def stack(self, extra=None):
        """Return the buffered frames as (C, n, m); ``extra`` (C, n) alone when empty."""
        if not self._frames:
            return extra[:, :, None]
        return np.stack(self._frames, axis=2)

    def keep_newest(self, count):
        """Drop all but the newest ``count`` frames; return how many remain."""
        recent = list(zip(self._ids, self._frames))[-count:]
        self._frames.clear()
        self._ids.clear()
        for frame_id, columns in recent:
            self.append(columns, frame_id)
        return len(recent)

    def resize(self, capacity):
        """Keep at most ``capacity`` frames from now on, the newest first."""
        if capacity != self.capacity:
            self._frames = deque(self._frames, maxlen=int(capacity))
            self._ids = deque(self._ids, maxlen=int(capacity))

    def rescale(self, old_shape, new_shape):
        """Resample every buffered frame from processing shape ``old_shape`` to ``new_shape``."""
        old_rows, old_cols, channels = old_shape
        rows, cols = new_shape[:2]
        resampled = deque(maxlen=self.capacity)
        for columns in self._frames:
            image = columns.T.reshape(old_rows, old_cols, channels)
            image = resize(image, (rows, cols)).reshape(rows * cols, channels)
            resampled.append(np.ascontiguousarray(image.T))
        self._frames = resampled


class SceneChangeWatch:
    """
    Tell when the scene itself changed: two consecutive masks over a foreground fraction.

    A light switched on, an exposure jump or a bumped camera marks most of a
    frame as foreground; the window is then restarted from the newest
    :attr:`FRAMES` frames. A fraction of 1.0 disables the rule.
    """

    #: Consecutive changed frames that make a scene change, and the frames kept.
    FRAMES = 2

    def __init__(self):
        self.changed_frames = 0

    def observe(self, mask, fraction):
        """Count one frame's mask; return True when the window should restart."""
        if fraction >= 1:
            return False
        share = np.count_nonzero(mask) / mask.size
        self.changed_frames = self.changed_frames + 1 if share > fraction else 0
        if self.changed_frames >= self.FRAMES:
            self.changed_frames = 0
            return True
        return False
