# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The foreground decision: each pixel against its own noise level.

One threshold for the whole frame treats a flickering monitor and a flat
wall alike. Here every pixel gets ``k`` times its own noise level ``sigma_p``,
read from the last window solve: the median of ``|D - L|`` (largest over the
colour channels) over the window's columns in which the pixel was observed
(its frame's mask called it background, see
:mod:`~dgmod_ros.core.streaming.background_memory`), times 1.4826 (the
standard deviation for Gaussian noise). Leaving out the columns the masks
called foreground keeps a passing person from raising the level, which a
median alone does only while the person is in fewer than half of the
columns: a young window of a few consecutive frames often has a walker in
most of them. A pixel observed in fewer than half of the columns takes the
median over all of them instead: the masks, not the pixel, are in doubt
there (leaves that the first masks took for foreground keep their level).
No pixel is taken as quieter than the frame's typical pixel (the median of
``sigma_p`` over the frame): only noisy places get a higher threshold, and a
pixel seen fewer than :data:`MIN_OBSERVED` times gets the typical level. The
levels are smoothed by the median of a 5 x 5 neighbourhood, which shares the
noise of a surface (leaves, a screen) without spreading a region's level
over its border (a box filter carried a walker's raised level 2 pixels out,
into the pixels where the walker comes next).

A frame's distance to its background is the largest absolute difference
over the channels (colour catches a person whose grey level matches the
wall). The binary decision is cleaned by a median filter (a majority vote of
the neighbourhood: fills pinholes, removes specks, keeps thin limbs better
than an opening) and brought to the input size by bilinear interpolation of
the 0/255 mask, thresholded at half.
"""

import math

import cv2
import numpy as np

from .blobs import BlobMotion
from .coherence import mean_field_mask
from .texture import descriptor_distance, RELATIVE_THRESHOLD
from .warmup_kernel import difference_magnitudes
from ..linalg import row_median
from ..masks import robust_sigma

#: Observations a pixel needs for its own noise level.
MIN_OBSERVED = 3
# Gaussian consistency factor of the median absolute value.
_MAD_TO_SIGMA = 1.4826
# Side of the median filter that smooths the noise levels (3 or 5: float32 input).
_NOISE_SMOOTHING = 5
# Smallest noise level: one grey level of 8-bit data.
_QUANTUM = 1.0 / 255.0
# A blob with fewer of its pixels changed over the last frames than this share is still.
_GHOST_MOVING_SHARE = 0.1


def observed_median(magnitude, observed=None):
    """
    Return each row's median (n,) over its observed entries, and their count (n,).

    With ``observed`` None, numpy's median of the whole row (the mean of the
    middle two for an even count), taken from a sort
    (:func:`~dgmod_ros.core.linalg.row_median`): ``np.median`` along the
    short rows of an (n, m) array is about 4x slower. Otherwise the lower
    median of the observed entries. The magnitudes are float32 and finite (a
    solve's residual), so sorting and ``np.median`` agree.
    """
    if observed is None:
        return row_median(magnitude), np.full(magnitude.shape[0], magnitude.shape[1])
    from .noise_kernel import observed_rows     # numba: loaded on first use
    filled, count = observed_rows(magnitude, observed)
    ordered = np.sort(filled, axis=1)           # unobserved entries (inf) last
    return ordered[np.arange(ordered.shape[0]), np.maximum(count - 1, 0) // 2], count


def pixel_noise(residual, shape, observed=None, uniform=False, sample=None):
    """
    Return each pixel's noise level ``sigma_p`` (n,) float32 from a window's residual.

    Parameters
    ----------
    residual : ndarray (C, n, m)
        ``D - L`` of the window; with ``sample``, of its sampled pixels only (C, k, m).
    shape : tuple (rows, cols, C)
        Processing shape.
    observed : ndarray (n, m) bool or None
        Entries counted in the level: the frame's own pixel, where its mask
        called it background (with ``sample``: (k, m)); None: all.
    uniform : bool
        Give every pixel the typical level (the ablation of the per-pixel rule).
    sample : PixelSample or None
        The levels are read at ``sample``'s pixels, a coarser grid of the
        frame (:class:`~dgmod_ros.core.streaming.solve_resolution.PixelSample`),
        and upsampled to ``shape`` before the smoothing; None: at every pixel.

    """
    return magnitude_noise(np.abs(residual).max(axis=0), shape, observed, uniform, sample)


def magnitude_noise(magnitude, shape, observed=None, uniform=False, sample=None):
    """
    Return :func:`pixel_noise` from the magnitude of the residual (n, m).

    ``magnitude`` is ``|D - L|``, largest over the channels, for a caller
    that has it already, or a non-negative statistic of its own (the
    chromaticity distance); the other parameters are :func:`pixel_noise`'s.
    """
    rows, cols = shape[:2]
    median, count = observed_median(magnitude, observed)
    if observed is not None:
        doubtful = count < magnitude.shape[1] / 2
        if doubtful.any():
            median[doubtful] = observed_median(magnitude[doubtful])[0]
            count[doubtful] = magnitude.shape[1]
    sigma = _MAD_TO_SIGMA * median
    seen = count >= MIN_OBSERVED
    typical = float(np.median(sigma[seen])) if np.any(seen) else robust_sigma(magnitude)
    typical = max(typical, _QUANTUM)
    if uniform:
        return np.full(rows * cols, typical, dtype=np.float32)
    sigma = np.where(seen, np.maximum(sigma, typical), typical).astype(np.float32)
    if sample is not None:
        # Upsampled unsmoothed, so that the smoothing below spans the same
        # neighbourhood of the frame as at every pixel.
        sigma = sample.upsample(sigma)
    smooth = cv2.medianBlur(sigma.reshape(rows, cols), _NOISE_SMOOTHING)
    return smooth.ravel()


def warmup_noise(frames):
    """
    Return one noise level for every pixel before the first solve, from frame differences.

    ``frames`` are the buffered frames and the frame itself, each (C, n),
    oldest first. The level is read like :func:`pixel_noise` reads the
    residual: 1.4826 times the median magnitude (largest over the channels)
    of the differences of consecutive frames, over all pixels, divided by
    sqrt(2) (a difference holds the noise of two frames). The magnitudes are
    not centred on their median first: their spread around their median
    says how alike they are, not how large, and a frame-wide change of a few
    grey levels (an exposure step between the first frames) then gave a
    level near 0 and a mask full of specks. A Python float, as every level
    the decision takes as one number: the decision then computes in
    float32, as with each pixel's own levels.
    """
    if len(frames) < 2:
        return _QUANTUM
    differences = difference_magnitudes(frames)
    median = float(np.median(differences, overwrite_input=True))    # a temporary
    return max(_MAD_TO_SIGMA * median / math.sqrt(2.0), _QUANTUM)


def moving_texture_k(columns, background, earlier, noise, k, weak_k, min_bits, shape,
                     distance=None):
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

    """
    rows, cols, channels = shape
    if distance is None:
        distance = np.abs(columns - background).max(axis=0)
    level = np.broadcast_to(np.asarray(noise, dtype=np.float32), distance.shape)
    factor = np.full(distance.shape, k, dtype=np.float32)
    weak = (distance > weak_k * level) & (distance <= k * level)
    weak &= np.abs(columns - earlier).max(axis=0) > weak_k * level
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
                  lighting=None, chroma_level=None, earlier=None, weak_k=0.0, weak_bits=16):
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

    """
    rows, cols = shape[:2]
    distance = np.abs(columns - background).max(axis=0)
    factor = k
    if weak_k > 0 and earlier is not None:
        factor = moving_texture_k(columns, background, earlier, noise, k, weak_k, weak_bits,
                                  shape, distance)
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


def to_input_size(mask, output_shape):
    """
    Bring a 0/255 mask to ``output_shape`` by bilinear interpolation thresholded at half.

    An exact doubling (the default scale of 0.5) is a copy of each pixel to
    its 2 x 2 block: there every output pixel's bilinear weights are 9/16 on
    its nearest input pixel and 7/16 on the others together (the borders
    replicate), so the interpolation is over half exactly where that pixel
    is 255, within the fixed-point rounding of OpenCV's.
    """
    if mask.shape == tuple(output_shape):
        return mask
    if tuple(output_shape) == (2 * mask.shape[0], 2 * mask.shape[1]):
        return cv2.resize(mask, (output_shape[1], output_shape[0]),
                          interpolation=cv2.INTER_NEAREST)
    smooth = cv2.resize(mask, (output_shape[1], output_shape[0]),
                        interpolation=cv2.INTER_LINEAR)
    return np.where(smooth > 127, np.uint8(255), np.uint8(0))


def _edge_strength(image):
    return np.abs(cv2.Sobel(image, cv2.CV_32F, 1, 0)) + np.abs(cv2.Sobel(image, cv2.CV_32F, 0, 1))


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
