# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Each pixel's own noise level, read from a window solve (and before the first one).

One threshold for the whole frame treats a flickering monitor and a flat
wall alike: the decision (:mod:`~dgmod_ros.core.streaming.decision`) gives
every pixel ``k`` times its own noise level ``sigma_p``, read from the last
window solve: the median of ``|D - L|`` (largest over the
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
Where the columns hold a person in view while the window filled (a person
beside the robot at its start), that median is the person's own change
across the window, his pose and the folds of his clothes, and puts him
under the threshold for as long as those columns stay. Such a pixel takes
the level of the differences of consecutive columns instead (1.4826 times
their median magnitude over sqrt(2)) where that is lower, but not below
``doubtful_floor`` of the median over all columns: a person's clothes
change slowly from frame to frame, leaves flicker from one to the next and
keep their level.
A level is the scale of what the model does not explain from one column to
the next. Where a pixel's median exceeds ``offset_k`` times the level of the
differences of its consecutive columns, the model misses it by an amount
that holds or drifts slowly: an offset the window's background carries (a
person in view while the window filled, learnt in another pose; the blur of
a person who has moved on), which a level of its size would hide from the
decision. Such a pixel takes the level of its differences. Leaves and a
flickering screen change from one column to the next and keep their level;
a background that sways slowly (a period of seconds) reads as an offset
too, which is this rule's price (docs/results.md).
A pixel the conditional update has held out of half of the window's columns or
more (something stands there, or the masks call its flicker foreground) has
in those columns the model's own values, not the frame's, and their residual
says nothing of its noise: read from them, a flickering plant's level fell to
the typical pixel's, its flicker passed the threshold, was held out in turn,
and the phantom grew for minutes (docs/results.md). Such a pixel keeps its
last known level (:func:`known_levels`): the one read when a window of
conditional admissions last observed it. A level read while the window
still holds its fill, whose frames went in as they were, is not known: a
person in view from the first frame is in it.
No pixel is taken as quieter than the frame's typical pixel (the median of
``sigma_p`` over the frame, read before the offset rule: a recording that
copies most blocks exactly has steps of 0 nearly everywhere, and its
typical pixel is still the model's usual miss): only noisy places get a
higher threshold, and a pixel seen fewer than :data:`MIN_OBSERVED` times
gets the typical level. The
levels are smoothed by the median of a 5 x 5 neighbourhood, which shares the
noise of a surface (leaves, a screen) without spreading a region's level
over its border (a box filter carried a walker's raised level 2 pixels out,
into the pixels where the walker comes next). Before the first solve,
one level for all pixels is read from the differences of consecutive
frames (:func:`warmup_noise`).
"""

import math

import cv2
import numpy as np

from .kernels.warmup_background import difference_magnitudes
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
    from .kernels.noise_levels import observed_rows     # numba: loaded on first use
    filled, count = observed_rows(magnitude, observed)
    ordered = np.sort(filled, axis=1)           # unobserved entries (inf) last
    return ordered[np.arange(ordered.shape[0]), np.maximum(count - 1, 0) // 2], count


def pixel_noise(residual, shape, observed=None, uniform=False, sample=None,
                doubtful_floor=1.0, offset_k=0.0, known=None):
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
    doubtful_floor : float in [0, 1]
        A pixel observed in fewer than half of the columns takes the level of
        the differences of consecutive columns where that is lower than the
        level of all its columns, but not below this share of it; 1: the
        level of all its columns (the module's docstring says why).
    offset_k : float
        A pixel whose level exceeds this multiple of the level of the
        differences of its consecutive columns takes that level, but not
        below the frame's typical level (an offset of the model, not
        noise); 0: none does.
    known : ndarray (n,) float32 or None
        Each pixel's last known level (:func:`known_levels`; with
        ``sample``, at its pixels (k,)), NaN where none: a pixel observed in
        fewer than half of the columns takes it. None: none does.

    """
    return magnitude_noise(np.abs(residual).max(axis=0), shape, observed, uniform, sample,
                           residual, doubtful_floor, offset_k, known)


def magnitude_noise(magnitude, shape, observed=None, uniform=False, sample=None,
                    residual=None, doubtful_floor=1.0, offset_k=0.0, known=None):
    """
    Return :func:`pixel_noise` from the magnitude of the residual (n, m).

    ``magnitude`` is ``|D - L|``, largest over the channels, for a caller
    that has it already, or a non-negative statistic of its own (the
    chromaticity distance); ``residual`` (C, n, m) the signed residual it
    was taken from, whose consecutive differences a doubtful pixel's level
    may come from, or None (none does); the other parameters are
    :func:`pixel_noise`'s.
    """
    rows, cols = shape[:2]
    median, count = observed_median(magnitude, observed)
    stepped = residual is not None and residual.shape[2] >= 3
    # Every row's steps once when the offset rule reads them; else the doubtful rows' only.
    steps = _step_medians(residual) if stepped and offset_k else None
    doubtful = None
    if observed is not None:
        doubtful = _doubtful(count, magnitude.shape[1])
        if doubtful.any():
            median[doubtful] = observed_median(magnitude[doubtful])[0]
            count[doubtful] = magnitude.shape[1]
            if stepped and doubtful_floor < 1.0:
                own = (steps[doubtful] if steps is not None
                       else _step_medians(residual[:, doubtful]))
                median[doubtful] = np.maximum(np.minimum(median[doubtful], own),
                                              doubtful_floor * median[doubtful])
    sigma = _MAD_TO_SIGMA * median
    seen = count >= MIN_OBSERVED
    typical = float(np.median(sigma[seen])) if np.any(seen) else robust_sigma(magnitude)
    typical = max(typical, _QUANTUM)
    if steps is not None:
        # After the typical level, which stays every pixel's floor (the module's docstring).
        offset = median > offset_k * steps
        sigma[offset] = _MAD_TO_SIGMA * steps[offset]
    if known is not None and doubtful is not None:
        # After the typical level: a pixel held out by the masks does not set it.
        carried = doubtful & np.isfinite(known)
        sigma[carried] = known[carried]
        seen |= carried
    if uniform:
        return np.full(rows * cols, typical, dtype=np.float32)
    sigma = np.where(seen, np.maximum(sigma, typical), typical).astype(np.float32)
    if sample is not None:
        # Upsampled unsmoothed, so that the smoothing below spans the same
        # neighbourhood of the frame as at every pixel.
        sigma = sample.upsample(sigma)
    smooth = cv2.medianBlur(sigma.reshape(rows, cols), _NOISE_SMOOTHING)
    return smooth.ravel()


def known_levels(noise, observed, before=None, sample=None):
    """
    Return each pixel's last known level (n,) float32 after a solve; NaN where none.

    ``noise`` (n,) is the solve's levels, ``observed`` (n, m) bool (with
    ``sample``, (k, m) at its pixels) its window's observed entries (None:
    all), ``before`` (n,) the known levels before it (None: none). A pixel
    observed in at least half of the columns takes its new level; any other
    keeps the one it had (the module's docstring); with ``sample``, a
    pixel takes its new level only where every sampled pixel around it was
    so observed. The caller passes only windows of conditional admissions.
    """
    if observed is None:
        return np.asarray(noise, dtype=np.float32).copy()
    doubtful = _doubtful(observed.sum(axis=1), observed.shape[1]).astype(np.float32)
    if sample is not None:
        doubtful = sample.upsample(doubtful)    # exactly 0 where no sampled neighbour is
    if before is None:
        before = np.full(noise.shape, np.nan, dtype=np.float32)
    return np.where(doubtful == 0, noise, before).astype(np.float32)


def _doubtful(count, columns):
    """Return the pixels observed in fewer than half of ``columns`` columns (``count`` (n,))."""
    return count < columns / 2


def _step_medians(residual):
    """
    Return each row's median magnitude (n,) of the differences of consecutive columns.

    The magnitude is the largest over the channels of ``residual`` (C, n, m),
    divided by sqrt(2): a difference holds the noise of two columns.
    """
    differences = np.abs(np.diff(residual, axis=2)).max(axis=0)
    return row_median(differences) / math.sqrt(2.0)


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
