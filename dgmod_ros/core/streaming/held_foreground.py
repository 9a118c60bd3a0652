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
pass. The ghost test of :func:`~dgmod_ros.core.streaming.foreground.ghost_blobs`
catches a ghost whose outline is an edge of the background; one that
uncovers texture (a railing behind a plain sweater) has the stronger edges
in the frame and passes for an object.

What a ghost has and a stopped person has not is stillness: the uncovered
background holds only sensor noise, while a seated person breathes, turns a
head, shifts a hand. A blob is *still* when at most ``share`` of its pixels
changed by more than ``k`` noise levels against the frame a few frames
before. A pixel that has been in a still blob for ``still_frames``
consecutive frames is dropped from the mask and enters the window as it is,
which heals the background; a real object left behind and never touched
(a bag) goes the same way, earlier than ``absorb_frames``.
"""

from .blobs import BlobMotion


def still_blob_pixels(mask, frame, earlier, noise, k, share, blobs=None):
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
        Largest share of a blob's pixels that may change for the blob to be still.
    blobs : BlobMotion or None
        The blobs of ``mask`` (or of a mask from which :meth:`BlobMotion.drop`
        removed blobs) against ``earlier``, when already labelled.

    """
    if blobs is None:
        blobs = BlobMotion(mask, frame, earlier, noise)
    still = blobs.moving_share(k) <= share
    still[0] = False
    still &= ~blobs.dropped
    return blobs.pixels(still)
