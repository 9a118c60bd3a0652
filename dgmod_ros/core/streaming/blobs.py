# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The blobs of a frame's foreground and how much of each moved, labelled once per frame.

Both blob tests of the per-frame path, the ghost test
(:func:`~dgmod_ros.core.streaming.ghost.ghost_blobs`) and the still-blob
test (:mod:`~dgmod_ros.core.streaming.held_foreground`), ask of every
8-connected blob which share of its pixels changed against a frame a few
frames before, at two thresholds. :class:`BlobMotion` labels the mask once
and counts the changed pixels of the blobs in one compiled pass over the
labelled pixels only
(:func:`~dgmod_ros.core.streaming.kernels.blobs.moving_share`; the
background's pixels, most of a frame, are skipped). The ghost test drops
whole blobs, so the blobs left to the still test are the same labels less the dropped ones
(:meth:`BlobMotion.drop`).
"""

import cv2
import numpy as np

from .kernels.blobs import moving_share, moving_share_reference
from ..numba_setup import reference_unless


class BlobMotion:
    """
    The 8-connected blobs of a mask and, per noise multiple, the share of each that moved.

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        The frame's foreground at the processing size.
    frame, earlier : ndarray (C, n)
        The frame and a frame a few frames before.
    noise : ndarray (n,) or float
        Each pixel's noise level.

    Attributes
    ----------
    count : int
        Labels, 0 (the background) included.
    labels : ndarray (rows, cols) int32
        Each pixel's blob.
    dropped : ndarray (count,) bool
        Blobs removed from the mask by :meth:`drop`.

    """

    def __init__(self, mask, frame, earlier, noise):
        self.count, self.labels = cv2.connectedComponents(mask, connectivity=8)
        self.dropped = np.zeros(self.count, dtype=bool)
        self._frame, self._earlier, self._noise = frame, earlier, noise
        self._shares = {}
        self._sizes = None

    @property
    def sizes(self):
        """Per label (count,) int64 its pixels, label 0 (the background) included."""
        if self._sizes is None:
            self._sizes = np.bincount(self.labels.ravel(), minlength=self.count)
        return self._sizes

    def moving_share(self, k):
        """Return per label (count,) float64 the share of pixels changed by over ``k`` levels."""
        if k not in self._shares:
            self._shares[k] = self._compute_share(k)
        return self._shares[k]

    def _compute_share(self, k):
        return reference_unless(moving_share, moving_share_reference, self.labels, self.count,
                                self._frame, self._earlier, self._noise, k)

    def pixels(self, flags):
        """Return as (rows, cols) bool the pixels of the blobs whose ``flags`` (count,) are set."""
        if not flags.any():
            return np.zeros(self.labels.shape, dtype=bool)
        return flags[self.labels]

    def drop(self, flags, mask):
        """Clear, in ``mask``, the blobs whose ``flags`` are set; remember them as dropped."""
        if flags.any():
            mask[flags[self.labels]] = 0
            self.dropped |= flags


def blobs_of_at_least(mask, min_pixels):
    """
    Return the 8-connected blobs of ``mask`` (rows, cols) uint8 with ``min_pixels`` pixels or more.

    As uint8 0/1 (rows, cols); ``min_pixels`` 0 keeps every blob.
    """
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    large = stats[:, cv2.CC_STAT_AREA] >= min_pixels
    large[0] = False
    return large.astype(np.uint8)[labels]
