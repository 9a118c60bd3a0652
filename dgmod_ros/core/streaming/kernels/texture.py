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
foreground, by a serial numba kernel (no threads: it runs in the image
callback beside the solve thread's parallel kernels). The decision's
moving-texture rule (:mod:`~dgmod_ros.core.streaming.decision`) and the
lighting test (:mod:`~dgmod_ros.core.streaming.photometric`) read it;
numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.

References
----------
G.-A. Bilodeau, J.-P. Jodoin, N. Saunier, "Change detection in feature space
using local binary similarity patterns", CRV 2013.
P.-L. St-Charles, G.-A. Bilodeau, "Improving background subtraction using
local binary similarity patterns", WACV 2014 (LOBSTER).

"""

import numpy as np

from ...numba_setup import njit, register_pass

#: The 16 neighbours (row, col offsets) of the 5 x 5 double-cross pattern.
PATTERN = ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1),
           (-2, -2), (-2, 0), (-2, 2), (0, -2), (0, 2), (2, -2), (2, 0), (2, 2))
#: LBSP's relative similarity threshold (LOBSTER's published default, 0.365).
RELATIVE_THRESHOLD = 0.365
#: Largest offset of :data:`PATTERN` along a row or a column.
REACH = 2
#: :data:`PATTERN` as an (16, 2) array for the kernels.
OFFSETS = np.array(PATTERN, dtype=np.int64)


@njit(cache=True, nogil=True, inline='always')
def channel_bits(frame, background, channel, row, col, rows, cols, limit, offsets, window):
    """
    Count the differing LBSP bits of one channel at one pixel; the border is replicated.

    ``frame`` and ``background`` are (C, rows * cols); ``window`` holds the
    flat positions of the pattern's neighbours from the top-left corner of
    the pixel's 5 x 5 window (:func:`window_offsets`), used inside the border.
    """
    reference = background[channel, row * cols + col]
    count = 0
    if REACH <= row < rows - REACH and REACH <= col < cols - REACH:
        # Inside the border (most pixels): views from the window's corner, no clamping.
        corner = (row - REACH) * cols + col - REACH
        in_frame = frame[channel, corner:]
        in_background = background[channel, corner:]
        for o in range(window.shape[0]):
            count += ((abs(in_frame[window[o]] - reference) > limit)
                      != (abs(in_background[window[o]] - reference) > limit))
        return count
    for o in range(offsets.shape[0]):
        neighbour = (min(max(row + offsets[o, 0], 0), rows - 1) * cols
                     + min(max(col + offsets[o, 1], 0), cols - 1))
        count += ((abs(frame[channel, neighbour] - reference) > limit)
                  != (abs(background[channel, neighbour] - reference) > limit))
    return count


def window_offsets(cols):
    """Return the flat positions (16,) int64 of the pattern's neighbours from a window's corner."""
    return (OFFSETS[:, 0] + REACH) * cols + OFFSETS[:, 1] + REACH


@njit(cache=True, nogil=True)
def _hamming(frame, background, rows, cols, threshold, pixels, offsets, window, out):
    """Count the differing LBSP bits at each pixel, summed over the channels."""
    for index in range(pixels.shape[0]):
        row, col = pixels[index] // cols, pixels[index] % cols
        count = 0
        for channel in range(frame.shape[0]):
            count += channel_bits(frame, background, channel, row, col, rows, cols,
                                  threshold[channel, index], offsets, window)
        out[index] = count


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
    channels, rows, cols = frame.shape
    pixels = np.ascontiguousarray(pixels, dtype=np.int64)
    out = np.empty(pixels.shape[0], dtype=np.uint8)
    _hamming(np.ascontiguousarray(frame, dtype=np.float32).reshape(channels, rows * cols),
             np.ascontiguousarray(background, dtype=np.float32).reshape(channels, rows * cols),
             rows, cols, np.ascontiguousarray(threshold, dtype=np.float32), pixels, OFFSETS,
             window_offsets(cols), out)
    return out


def descriptor_distance_reference(frame, background, threshold, pixels):
    """Return :func:`descriptor_distance` computed in numpy, the border replicated by padding."""
    channels, rows, cols = frame.shape
    pixels = np.asarray(pixels, dtype=np.int64)
    row, col = pixels // cols + REACH, pixels % cols + REACH
    reach = ((0, 0), (REACH, REACH), (REACH, REACH))
    padded_frame = np.pad(np.asarray(frame, dtype=np.float32), reach, mode='edge')
    padded_background = np.pad(np.asarray(background, dtype=np.float32), reach, mode='edge')
    centre = padded_background[:, row, col]                        # (C, p)
    limit = np.asarray(threshold, dtype=np.float32)
    bits = np.zeros(pixels.shape[0], dtype=np.int64)
    for dr, dc in PATTERN:
        in_frame = np.abs(padded_frame[:, row + dr, col + dc] - centre) > limit
        in_background = np.abs(padded_background[:, row + dr, col + dc] - centre) > limit
        bits += (in_frame != in_background).sum(axis=0)
    return bits.astype(np.uint8)


def _examples():
    """Return a frame and its background with some pixels inside and on the border."""
    rng = np.random.default_rng(0)
    background = rng.uniform(0, 1, (3, 20, 30)).astype(np.float32)
    frame = background * rng.uniform(0.6, 1.4, background.shape).astype(np.float32)
    pixels = np.array([0, 1, 29, 31, 45, 300, 599, 570, 333])
    threshold = rng.uniform(0.01, 0.2, (3, pixels.size)).astype(np.float32)
    return [(frame, background, threshold, pixels)]


register_pass(descriptor_distance, _examples, descriptor_distance_reference)
