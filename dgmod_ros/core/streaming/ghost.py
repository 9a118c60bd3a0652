# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The ghost test: foreground blobs where the background is wrong, not where something is in front.

A still blob (its pixels match a frame a few frames before: the blob
labelling's :class:`~dgmod_ros.core.streaming.blobs.BlobMotion`) whose outline
is an edge of the background rather than of the frame is what has left the
window's frames, uncovering the place behind it (:func:`ghost_blobs`).

A ghost can also be one blob with what is leaving it (a person who stood
from the first frame walks off: the place he uncovers and he himself are
joined until he is a body width away). :func:`ghost_parts` asks the same
of the still parts of every blob, where the answer must hold pixel by
pixel along the part's outline: the background shows an edge across it and
the frame, holding still there, shows none.
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
    box = _box(mask, margin=2)
    border, owner = _outline(mask[box], blobs.labels[box])
    frame_edges = _edge_strength(_grey(frame, mask.shape, box))[border]
    background_edges = _edge_strength(_grey(background, mask.shape, box))[border]
    in_frame = np.bincount(owner, frame_edges, minlength=blobs.count)
    in_background = np.bincount(owner, background_edges, minlength=blobs.count)
    return ghost & (in_background > in_frame)


def ghost_parts(mask, frame, background, still, noise, k):
    """
    Return the pixels (rows, cols) bool of the still parts of foreground blobs that are ghosts.

    A part is an 8-connected region of the foreground's pixels that hold
    still (``still``). Along the outline of the foreground (its pixels
    within a pixel of the background) each outline pixel owned by a part
    reads the Sobel derivative of the frame and of the background across
    the outline (along its normal, from the smoothed mask): the background
    crosses an edge there when its derivative exceeds the frame's by more
    than ``k`` times the derivative's noise (``sqrt(12)`` noise levels for
    the 3 x 3 Sobel), the frame's own being within it and the frame holding
    still at that pixel. A part more than half of whose outline pixels show
    such an edge is a ghost: its outline belongs to what has left. Texture
    of the place that a person's outline happens to cross runs every way
    and is seen in the frame as well; a departed silhouette runs along the
    outline in the background only.

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        The frame's foreground at the processing size.
    frame, background : ndarray (C, n)
        The frame and its background.
    still : ndarray (n,) bool
        The pixels that hold still (against a frame a few frames before).
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k : float
        Multiple of the noise that makes an edge.

    """
    rows, cols = mask.shape
    ghosts = np.zeros((rows, cols), dtype=bool)
    still = np.asarray(still).reshape(rows, cols)
    if not (still & (mask > 0)).any():
        return ghosts
    # The outline's pixels and their derivatives read two pixels around the
    # blobs, the smoothed mask's normal two more: the box grown by 4 holds it.
    box = _box(mask, margin=4)
    boxed, still = mask[box], still[box]
    count, labels = cv2.connectedComponents(((boxed > 0) & still).astype(np.uint8),
                                            connectivity=8)
    outline, owner = _outline(boxed, labels)
    smooth = cv2.GaussianBlur(boxed.astype(np.float32), (5, 5), 0)
    normal_x, normal_y = cv2.Sobel(smooth, cv2.CV_32F, 1, 0), cv2.Sobel(smooth, cv2.CV_32F, 0, 1)
    length = np.hypot(normal_x, normal_y) + np.float32(1e-6)

    def across(image):
        grey = _grey(image, mask.shape, box)
        derivative = (cv2.Sobel(grey, cv2.CV_32F, 1, 0) * normal_x
                      + cv2.Sobel(grey, cv2.CV_32F, 0, 1) * normal_y)
        return (np.abs(derivative) / length)[outline]

    in_frame, in_background = across(frame), across(background)
    level = np.broadcast_to(np.asarray(noise, dtype=np.float32), (rows * cols,))
    margin = (k * np.sqrt(np.float32(12)) * level.reshape(rows, cols)[box])[outline]
    edge = ((in_background - in_frame > margin) & (in_frame < margin) & still[outline])
    shown = np.bincount(owner, edge, minlength=count)
    total = np.bincount(owner, minlength=count)
    ghost = 2 * shown > total
    ghost[0] = False
    ghosts[box] = ghost[labels]
    return ghosts


def _box(mask, margin):
    """Return the slices of ``mask``'s box around its nonzero pixels, grown by ``margin``."""
    rows, cols = mask.shape
    top, bottom = _span(mask.any(axis=1), rows, margin)
    left, right = _span(mask.any(axis=0), cols, margin)
    return np.s_[top:bottom, left:right]


def _outline(mask, labels):
    """
    Return the outline (rows, cols) bool of ``mask`` and each outline pixel's owner label.

    The outline is the pixels within a pixel of the mask's edge, on both
    sides; those just outside take a label of ``labels`` from a 3 x 3
    dilation (the largest one next to them).
    """
    square = np.ones((3, 3), np.uint8)
    outline = cv2.morphologyEx(mask, cv2.MORPH_GRADIENT, square) > 0
    owner = cv2.dilate(labels.astype(np.float32), square).astype(np.int32)[outline]
    return outline, owner


def _grey(image, shape, box):
    """Return the channel mean (rows, cols) in ``box`` of an image given as (C, n) columns."""
    return image.reshape((image.shape[0],) + tuple(shape))[(slice(None),) + box].mean(axis=0)


def _span(occupied, size, margin=2):
    """Return [first - margin, last + 1 + margin) of the True entries, clipped to [0, size)."""
    where = np.flatnonzero(occupied)
    return max(int(where[0]) - margin, 0), min(int(where[-1]) + 1 + margin, size)
