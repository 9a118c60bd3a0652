# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The blobs of a frame's foreground and how much of each moved, labelled once per frame.

Both blob tests of the per-frame path, the ghost test
(:func:`~dgmod_ros.core.streaming.foreground.ghost_blobs`) and the still-blob
test (:mod:`~dgmod_ros.core.streaming.held_foreground`), ask of every
8-connected blob which share of its pixels changed against a frame a few
frames before, at two thresholds. :class:`BlobMotion` labels the mask once
and counts the changed pixels of the blobs in one compiled pass over the
labelled pixels only (:func:`_moving_counts`; the background's pixels, most
of a frame, are skipped). The ghost test drops whole blobs, so the blobs left
to the still test are the same labels less the dropped ones
(:meth:`BlobMotion.drop`).

The shares are those of :func:`moving_share_reference`, the numpy
formulation, bit for bit (the background's label 0 aside, which no test
reads): the same float32 comparisons, integer counts, the same float64
division.
"""

import cv2
from numba import njit
import numpy as np

# numba's cache folder and threading layer, set before the decorators below run.
from .. import kernels  # noqa: F401


@njit(cache=True, nogil=True)
def _moving_counts(labels, frame, earlier, noise, k, pixels, moved):
    """
    Count each label's pixels and those whose change exceeds ``k`` noise levels.

    A change is the largest absolute difference over the channels (NaN in
    any channel: no change, as numpy's ``max`` then ``>``).
    """
    channels = frame.shape[0]
    for i in range(labels.shape[0]):
        label = labels[i]
        if label == 0:
            continue
        pixels[label] += 1
        change = np.float32(0.0)
        finite = True
        for c in range(channels):
            value = abs(frame[c, i] - earlier[c, i])
            if value != value:
                finite = False
            elif value > change:
                change = value
        if finite and change > k * noise[i]:
            moved[label] += 1


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

    def moving_share(self, k):
        """Return per label (count,) float64 the share of pixels changed by over ``k`` levels."""
        if k not in self._shares:
            self._shares[k] = self._compute_share(k)
        return self._shares[k]

    def _compute_share(self, k):
        noise, frame, earlier = self._noise, self._frame, self._earlier
        # The kernel reproduces float32 arithmetic: float32 data, a float32
        # level per pixel and a Python k (numpy takes it as float32).
        if (type(k) in (float, int) and isinstance(noise, np.ndarray)
                and noise.dtype == np.float32 and noise.size == self.labels.size
                and frame.dtype == np.float32 and earlier.dtype == np.float32):
            pixels = np.zeros(self.count, dtype=np.int64)
            moved = np.zeros(self.count, dtype=np.int64)
            _moving_counts(self.labels.reshape(-1), np.ascontiguousarray(frame),
                           np.ascontiguousarray(earlier), np.ascontiguousarray(noise.ravel()),
                           np.float32(k), pixels, moved)
            return moved / np.maximum(pixels, 1)
        return moving_share_reference(self.labels, self.count, frame, earlier, noise, k)

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


def moving_share_reference(labels, count, frame, earlier, noise, k):
    """Return :meth:`BlobMotion.moving_share` computed in numpy (what the tests compare with)."""
    flat = labels.ravel()
    moved = np.abs(frame - earlier).max(axis=0) > k * noise
    return (np.bincount(flat, moved, minlength=count)
            / np.maximum(np.bincount(flat, minlength=count), 1))


def compile_kernel():
    """Compile (or load from the cache) the counting pass on a tiny input."""
    mask = np.zeros((2, 3), dtype=np.uint8)
    mask[0, 0] = 255
    frame = np.zeros((1, 6), dtype=np.float32)
    BlobMotion(mask, frame, frame, np.ones(6, dtype=np.float32)).moving_share(1.0)
