# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Local texture against the background: the LBSP descriptor distance.

A Local Binary Similarity Pattern (Bilodeau et al.) describes a pixel by 16
bits, one per neighbour of a 5 x 5 double cross: whether the neighbour's value
differs from a reference value by more than a threshold. LOBSTER and SuBSENSE
compare a frame with its background by computing both patterns with the
*background's* centre value as the reference (the frame's "inter" pattern)
and counting the bits that differ (the Hamming distance). With a threshold
relative to that value (:data:`RELATIVE_THRESHOLD` of it), light that scales a
neighbourhood by less than that share (a shadow's or a reflection's interior)
flips no bit; a body with its own edges and shades flips many.

Each colour channel gets its own pattern; the distances add up over the
channels (0 to 16 C bits). The distance is computed only at the pixels asked
for (the decision's candidates), which keeps its cost proportional to the
foreground.

References
----------
G.-A. Bilodeau, J.-P. Jodoin, N. Saunier, "Change detection in feature space
using local binary similarity patterns", CRV 2013.
P.-L. St-Charles, G.-A. Bilodeau, "Improving background subtraction using
local binary similarity patterns", WACV 2014 (LOBSTER).

"""

import cv2
import numpy as np

#: The 16 neighbours (row, col offsets) of the 5 x 5 double-cross pattern.
PATTERN = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1),
           (-2, -2), (-2, 0), (-2, 2), (0, -2), (0, 2), (2, -2), (2, 0), (2, 2))
#: LBSP's relative similarity threshold (LOBSTER's published default, 0.365).
RELATIVE_THRESHOLD = 0.365
_REACH = 2


def _padded_flat(image):
    """Return a (C, rows, cols) image with its border replicated by the pattern's reach, flat."""
    return np.stack([cv2.copyMakeBorder(channel, _REACH, _REACH, _REACH, _REACH,
                                        cv2.BORDER_REPLICATE).ravel() for channel in image])


def descriptor_distance(frame, background, threshold, pixels):
    """
    Return the LBSP Hamming distance between a frame and its background at some pixels.

    Parameters
    ----------
    frame, background : ndarray (C, rows, cols) float32
        The frame and its background at the processing size.
    threshold : ndarray (C, p) float32
        Smallest difference to the background's centre value that sets a bit,
        per channel and pixel.
    pixels : ndarray (p,) int
        Flat (row-major) indices of the pixels to describe.

    Returns
    -------
    ndarray (p,) uint8
        Bits that differ, summed over the channels.

    """
    frame = np.asarray(frame, dtype=np.float32)
    background = np.asarray(background, dtype=np.float32)
    cols = frame.shape[2]
    width = cols + 2 * _REACH
    pixels = np.asarray(pixels)
    centre = (pixels // cols + _REACH) * width + pixels % cols + _REACH
    frame_flat, background_flat = _padded_flat(frame), _padded_flat(background)
    reference = background_flat[:, centre]
    distance = np.zeros(reference.shape, dtype=np.uint8)
    for dr, dc in PATTERN:
        neighbour = centre + dr * width + dc
        in_frame = np.abs(frame_flat[:, neighbour] - reference) > threshold
        in_background = np.abs(background_flat[:, neighbour] - reference) > threshold
        distance += in_frame != in_background
    return distance.sum(axis=0, dtype=np.uint8)
