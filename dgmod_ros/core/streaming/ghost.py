# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The ghost test: foreground blobs where the background is wrong, not where something is in front.

A still blob (its pixels match a frame a few frames before: the blob
labelling's :class:`~dgmod_ros.core.streaming.blobs.BlobMotion`) whose outline
is an edge of the background rather than of the frame is what has left the
window's frames, uncovering the place behind it (:func:`ghost_blobs`).
"""

import cv2
import numpy as np

from .blobs import BlobMotion

# A blob with fewer of its pixels changed over the last frames than this share is still.
_GHOST_MOVING_SHARE = 0.1


def _edge_strength(image):
    return np.abs(cv2.Sobel(image, cv2.CV_32F, 1, 0)) + np.abs(cv2.Sobel(image, cv2.CV_32F, 0, 1))


def ghost_blobs(mask, frame, background, earlier, noise, k, blobs=None):
    """
    Return the pixels (rows, cols) bool of foreground blobs that are ghosts.

    A ghost is a blob where the background is wrong (something that was in
    the window's frames has left), not where something is in front of it.
    Two tests, both required: the blob is still (its pixels match the frame
    ``earlier`` within ``k`` noise levels: a walking person fails this), and
    its outline is an edge of the background rather than of the frame (the
    summed gradient magnitude along the blob's border is larger in the
    background image: the edges belong to what has left).

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        The frame's foreground at the processing size.
    frame, background, earlier : ndarray (C, n)
        The frame, its background and a frame a few frames before.
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k : float
        Multiple of the noise level that counts as a change.
    blobs : BlobMotion or None
        The blobs of ``mask`` against ``earlier`` when already labelled.

    """
    if blobs is None:
        blobs = BlobMotion(mask, frame, earlier, noise)
    return blobs.pixels(ghost_labels(blobs, mask, frame, background, k))


def ghost_labels(blobs, mask, frame, background, k):
    """Return per blob (count,) bool whether it is a ghost (see :func:`ghost_blobs`)."""
    ghost = blobs.moving_share(k) < _GHOST_MOVING_SHARE
    ghost[0] = False
    if not ghost.any():                 # no still blob: the edges cannot make one a ghost
        return ghost
    # The borders lie within a pixel of the blobs and their gradients read one
    # pixel further: the frame's box around the blobs grown by 2 holds all
    # that the test reads (the operations are per pixel, the same in the box).
    rows, cols = mask.shape
    top, bottom = _span(mask.any(axis=1), rows)
    left, right = _span(mask.any(axis=0), cols)
    box = np.s_[top:bottom, left:right]
    square = np.ones((3, 3), np.uint8)
    border = cv2.morphologyEx(mask[box], cv2.MORPH_GRADIENT, square) > 0
    # Border pixels just outside a blob take the blob's label from a 3 x 3 dilation.
    owner = cv2.dilate(blobs.labels[box].astype(np.float32), square)
    owner = owner.astype(np.int32)[border]
    channels = frame.shape[0]
    frame_edges = _edge_strength(frame.reshape(channels, rows, cols)[(slice(None),) + box]
                                 .mean(axis=0))[border]
    background_edges = _edge_strength(
        background.reshape(channels, rows, cols)[(slice(None),) + box].mean(axis=0))[border]
    in_frame = np.bincount(owner, frame_edges, minlength=blobs.count)
    in_background = np.bincount(owner, background_edges, minlength=blobs.count)
    return ghost & (in_background > in_frame)


def _span(occupied, size, margin=2):
    """Return [first - margin, last + 1 + margin) of the True entries, clipped to [0, size)."""
    where = np.flatnonzero(occupied)
    return max(int(where[0]) - margin, 0), min(int(where[-1]) + 1 + margin, size)
