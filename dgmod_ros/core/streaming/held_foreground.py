# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Foreground that nothing moves in: the ghosts the conditional update would hold.

The conditional update (:mod:`~dgmod_ros.core.streaming.background_memory`)
keeps a frame's foreground out of the window so that a person who stops stays
foreground. Its blind spot is a ghost: something that was in the window's
frames when the model was learnt (a person standing in the first frames)
leaves, the place it uncovers is foreground, and being foreground it is never
admitted, so the window keeps the departed object until ``absorb_frames``
pass. The ghost test of :func:`~dgmod_ros.core.streaming.ghost.ghost_blobs`
catches a ghost whose outline is an edge of the background; one that
uncovers texture (a railing behind a plain sweater) has the stronger edges
in the frame and passes for an object.

What a ghost has and a stopped person has not is stillness: the uncovered
background holds only sensor noise, while a seated person breathes, turns a
head, shifts a hand. A blob is *still* when at most ``share`` of its pixels
(or one pixel, whatever its size) changed by more than ``k`` noise levels
against the frame a few frames before. A pixel that has been in a still
blob for ``still_frames`` consecutive frames is dropped from the mask and
enters the window as it is, which heals the background.

Stillness alone does not tell a ghost from a person who stops dead (a
person standing still beside the robot, a bag put down): what the scene
showed does. Something that came in moved over the pixels it now covers
while they were already foreground (a body walking in changes the pixels it
passes over); the place a ghost uncovers holds the background, which does
not move once uncovered. A blob most of whose pixels moved while foreground
(:func:`moved_inside`, :func:`came_in`) is never still: it stays foreground
until ``absorb_frames``.
"""

import numpy as np

from .blobs import BlobMotion


def moved_inside(foreground, foreground_age, change, noise, k, lag):
    """
    Return the pixels (n,) bool that changed while they were already foreground.

    A pixel is foreground now and was for the ``lag`` frames before
    (``foreground_age``, the count up to the frame before, at least ``lag``),
    and its ``change`` (n,) against the frame ``lag`` frames before (the
    largest absolute difference over the channels) exceeds ``k`` noise
    levels: something in front of the background moved over it. The place a
    ghost uncovers holds the background, which does not move once uncovered.
    """
    flat = foreground.ravel() > 0
    if foreground_age is None or foreground_age.shape != flat.shape:
        return np.zeros(flat.shape, dtype=bool)
    return flat & (foreground_age >= lag) & (change > k * np.asarray(noise, dtype=np.float32))


def came_in(blobs, entered):
    """
    Return per blob (count,) bool whether it was seen to come in.

    ``entered`` (n,) bool marks the pixels that have moved while foreground
    (:func:`moved_inside`, held while they stay foreground). A blob most of
    whose pixels did is something that came in and stopped; a ghost's
    pixels never moved after it appeared.
    """
    labels = blobs.labels.ravel()
    inside = np.bincount(labels[entered.ravel()], minlength=blobs.count)
    return 2 * inside > blobs.sizes


def still_blob_pixels(mask, frame, earlier, noise, k, share, blobs=None, entered=None):
    """
    Return the pixels (rows, cols) bool of foreground blobs in which nothing moved.

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        The frame's foreground at the processing size.
    frame, earlier : ndarray (C, n)
        The frame and a frame a few frames before.
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k : float
        Multiple of the noise level that counts as a change.
    share : float
        Largest share of a blob's pixels that may change for the blob to be
        still; one pixel may change in a blob of any size.
    blobs : BlobMotion or None
        The blobs of ``mask`` (or of a mask from which :meth:`BlobMotion.drop`
        removed blobs) against ``earlier``, when already labelled.
    entered : ndarray (n,) bool or None
        The pixels that moved while foreground (:func:`came_in`): a blob
        seen to come in is never still. None: no blob is exempt.

    """
    if blobs is None:
        blobs = BlobMotion(mask, frame, earlier, noise)
    # One pixel past k levels is allowed whatever the blob's size: below 1 / share
    # pixels the share would ask every pixel to hold, and one pixel of sensor
    # noise every few frames would keep restarting a small ghost's count.
    one_pixel = 1.0 / np.maximum(blobs.sizes, 1)
    still = blobs.moving_share(k) <= np.maximum(share, one_pixel)
    still[0] = False
    still &= ~blobs.dropped
    if entered is not None and still.any():
        still &= ~came_in(blobs, entered)
    return blobs.pixels(still)


def consecutive_frames(previous, flags):
    """
    Return for each pixel the consecutive frames (n,) int32 its flag has held.

    ``previous`` is the count of the frame before (None or another shape:
    start from zero); a pixel whose flag is off restarts at 0.
    """
    flags = np.asarray(flags).ravel()
    if previous is None or previous.shape != flags.shape:
        previous = np.zeros(flags.shape, dtype=np.int32)
    return np.where(flags, previous + 1, 0).astype(np.int32)
