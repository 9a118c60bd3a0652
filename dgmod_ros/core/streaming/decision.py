# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The foreground decision: each pixel's distance to its background against its noise level.

A frame's distance to its background is the largest absolute difference
over the channels (colour catches a person whose grey level matches the
wall); a pixel is a candidate where it exceeds ``k`` times the pixel's own
noise level (:mod:`~dgmod_ros.core.streaming.noise_levels`), or a lower
multiple where a texture moved (:func:`moving_texture_k`). The lighting test
(:mod:`~dgmod_ros.core.streaming.photometric`) drops what light explains,
and the binary decision is cleaned by a median filter (a majority vote of
the neighbourhood: fills pinholes, removes specks, keeps thin limbs better
than an opening) or decided by the Potts field
(:mod:`~dgmod_ros.core.streaming.coherence`) instead.
"""

import cv2
import numpy as np

from .coherence import mean_field_mask
from .kernels.texture import descriptor_distance, RELATIVE_THRESHOLD


def moving_texture_k(columns, background, earlier, noise, k, weak_k, min_bits, shape,
                     distance=None, change=None):
    """
    Return each pixel's multiple of its noise level (n,) float32: ``weak_k`` where texture moved.

    A pixel whose colour matches what is behind it (a dark torso before a
    dark doorway) stays within ``k`` noise levels of its background, but a
    body brings its own pattern of shades and it moves. A pixel between
    ``weak_k`` and ``k`` noise levels from its background is held to
    ``weak_k`` instead of ``k`` when both hold:

    - its LBSP descriptor (:mod:`~dgmod_ros.core.streaming.texture`, the
      threshold of a bit the larger of the relative one and ``weak_k``
      noise levels) differs from the background's in at least ``min_bits``
      bits: the neighbourhood's pattern changed, which light alone does not
      do and which a colour match does not hide;
    - it changed by more than ``weak_k`` noise levels against ``earlier``
      (a frame a few frames before): a ghost of something that has left,
      and the texture it uncovers, do not move.

    Parameters
    ----------
    columns, background, earlier : ndarray (C, n)
        The frame, its background and a frame a few frames before.
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k, weak_k : float
        The multiple of the noise level that makes a pixel foreground, and the
        lower one for moving texture (``weak_k >= k`` gives ``k`` everywhere).
    min_bits : int
        Fewest differing LBSP bits (of ``16 C``) that count as a changed texture.
    shape : tuple (rows, cols, C)
        Processing shape.
    distance : ndarray (n,) or None
        ``|columns - background|``, largest over the channels, if already computed.
    change : ndarray (n,) or None
        ``|columns - earlier|``, largest over the channels, if already computed.

    """
    rows, cols, channels = shape
    if distance is None:
        distance = np.abs(columns - background).max(axis=0)
    if change is None:
        change = np.abs(columns - earlier).max(axis=0)
    level = np.broadcast_to(np.asarray(noise, dtype=np.float32), distance.shape)
    factor = np.full(distance.shape, k, dtype=np.float32)
    weak = (distance > weak_k * level) & (distance <= k * level)
    weak &= change > weak_k * level
    pixels = np.flatnonzero(weak)
    if pixels.size == 0:
        return factor
    reference = background[:, pixels]
    threshold = np.maximum(RELATIVE_THRESHOLD * reference, weak_k * level[pixels])
    bits = descriptor_distance(columns.reshape(channels, rows, cols),
                               background.reshape(channels, rows, cols), threshold, pixels)
    factor[pixels[bits >= min_bits]] = weak_k
    return factor


def adaptive_mask(columns, background, noise, k, shape, median_size, mrf_beta=0.0,
                  lighting=None, chroma_level=None, earlier=None, weak_k=0.0, weak_bits=16,
                  change=None):
    """
    Return a frame's foreground at the processing size (uint8 0/255) and its distance.

    Parameters
    ----------
    columns, background : ndarray (C, n)
        The frame and its background.
    noise : ndarray (n,) or float
        Each pixel's noise level.
    k : float
        Multiple of the noise level that makes a pixel foreground.
    shape : tuple (rows, cols, C)
        Processing shape.
    median_size : int
        Side of the median filter (odd); <= 1 disables it.
    mrf_beta : float
        > 0: the Potts field of :func:`~dgmod_ros.core.streaming.coherence.mean_field_mask`
        with this coupling decides instead of the threshold and the median filter.
    lighting : LightingTest or None
        Drops the changes that light explains
        (:class:`~dgmod_ros.core.streaming.photometric.LightingTest`); None keeps all.
        Under the field, an explained pixel counts as background evidence (distance 0).
    chroma_level : ndarray (n,) or None
        Each pixel's chromaticity noise level, for ``lighting``.
    earlier : ndarray (C, n) or None
        A frame a few frames before, for the moving-texture rule.
    weak_k : float
        > 0 (and ``earlier`` given): pixels whose texture changed and moved
        are held to this multiple of their noise level instead of ``k``
        (:func:`moving_texture_k`); 0 disables.
    weak_bits : int
        Fewest differing LBSP bits of a changed texture (``weak_k`` > 0).
    change : ndarray (n,) or None
        ``|columns - earlier|``, largest over the channels, if already computed.

    """
    rows, cols = shape[:2]
    distance = np.abs(columns - background).max(axis=0)
    factor = k
    if weak_k > 0 and earlier is not None:
        factor = moving_texture_k(columns, background, earlier, noise, k, weak_k, weak_bits,
                                  shape, distance, change)
    changed = distance > factor * noise
    evidence = distance
    if lighting is not None:
        explained = lighting.explains(columns, background, noise, k, shape, changed,
                                      chroma_level)
        changed &= ~explained
        evidence = np.where(explained, np.float32(0), distance)
    if mrf_beta > 0:
        mask = mean_field_mask(evidence, noise, factor, mrf_beta, shape)
        return mask, distance.reshape(rows, cols)
    mask = np.where(changed, np.uint8(255), np.uint8(0)).reshape(rows, cols)
    if median_size > 1:
        mask = cv2.medianBlur(mask, int(median_size))
    return mask, distance.reshape(rows, cols)
