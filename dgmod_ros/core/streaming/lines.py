# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Blobs that are lines, not bodies: left out of the published mask.

An edge of the scene that shifts by a fraction of a pixel (the rim of a
ceiling light that grows and shrinks with the camera's exposure, a cable's
shadow on sunlit ground) changes a band one or two pixels wide along the
whole edge: each of its pixels is far from its background by many noise
levels, and the Potts field keeps the band because its pixels back each
other along it. A body is thick: at the processing size (a frame of at most
``processing_pixels``) even a far person holds a 3 x 3 square of foreground
somewhere. A blob that holds none is a line, and when it is large enough to
be an obstacle to the planner it leaves the mask. Large enough is counted in
the camera's pixels (:func:`processing_pixels_of`), which is what the
planner receives: one point per pixel. Smaller blobs are left alone: slivers
of a person that the background half holds (a person who stood from the
first frame, a far walker's limbs) are that size.

The rule only thins what is published. The window still keeps the line's
pixels out (a limb cut off from its body must not be learnt as background);
measured the other way, a far walker's slivers entered the window and his
recall fell (``docs/results.md``).
"""

import cv2
import numpy as np

_CORE = np.ones((3, 3), dtype=np.uint8)


def processing_pixels_of(camera_pixels, processing_shape, input_shape):
    """Return the processing pixels (float) a blob of ``camera_pixels`` input pixels covers."""
    return (camera_pixels * float(processing_shape[0] * processing_shape[1])
            / float(input_shape[0] * input_shape[1]))


def without_lines(mask, min_pixels):
    """
    Return ``mask`` without its line blobs (a new array; ``mask`` itself when there are none).

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        0/255 foreground at the processing size.
    min_pixels : float
        Fewest pixels of an 8-connected blob that holds no 3 x 3 square of
        foreground for it to be a line; 0 keeps every blob.

    """
    if min_pixels <= 0 or not mask.any():
        return mask
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    body = np.zeros(count, dtype=bool)
    body[labels[cv2.erode(mask, _CORE) > 0]] = True
    line = ~body & (np.bincount(labels.ravel(), minlength=count) >= min_pixels)
    line[0] = False
    if not line.any():
        return mask
    return np.where(line[labels], np.uint8(0), mask)
