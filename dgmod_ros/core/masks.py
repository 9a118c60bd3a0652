# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The one rule that turns a foreground estimate into a binary mask.

Every method in the package goes through :class:`MaskRule`, so comparisons
measure the separation, not the thresholding.

Rule: a pixel is foreground when the magnitude of its foreground estimate
(``|S|``; for colour, the largest over the channels) exceeds a threshold
``tau``. With ``threshold='auto'``, ``tau = max(min_threshold, k * sigma)``
where ``sigma = 1.4826 * MAD(R)`` is a robust estimate of the noise level of
the residual ``R = D - L`` over the whole window (MAD: median absolute
deviation from the median; 1.4826 makes it the standard deviation for
Gaussian noise). When the window's frames are given too, ``sigma`` is at most
``1.4826 * MAD(d_t - d_(t-1)) / sqrt(2)``, the same estimate from consecutive
frame differences, which does not depend on how well ``L`` fits: a background
that lags behind a light change inflates the residual's MAD, never the
differences' (``docs/solver.md`` has the case that showed it). The magnitude
is resized to the output size (bilinear) before thresholding, then an
optional morphological opening (speckle) and closing (holes) with an elliptic
``morph_size x morph_size`` kernel is applied.
"""

import cv2
import numpy as np

from .preprocess import to_uint8
from .validation import NON_NEGATIVE, NON_NEGATIVE_INTEGER, Options, POSITIVE, validate_params

# Enough samples for a stable median; larger windows are subsampled with a
# fixed stride so that the estimate is deterministic.
_MAD_SAMPLES = 200_000


def robust_sigma(values):
    """``1.4826 * median(|x - median(x)|)`` over a deterministic subsample."""
    flat = np.asarray(values, dtype=np.float32).ravel()
    if flat.size == 0:
        return 0.0
    if flat.size > _MAD_SAMPLES:
        flat = flat[::flat.size // _MAD_SAMPLES + 1]
    center = np.median(flat)
    return float(1.4826 * np.median(np.abs(flat - center)))


class MaskRule:
    """
    Threshold plus clean-up that makes masks from foreground magnitudes.

    Parameters
    ----------
    threshold : float or 'auto', default='auto'
        Fixed ``tau`` on data in [0, 1], or 'auto' for the residual-based rule.
    k : float, default=5.0
        Multiple of the robust noise level used by the 'auto' rule.
    min_threshold : float, default=0.1
        Floor of the 'auto' threshold, so a noiseless scene does not flag
        compression artefacts.
    morph_size : int, default=3
        Kernel side of the opening and closing; 0 or 1 disables clean-up.

    """

    _parameter_constraints = {
        'threshold': (Options('auto'), *POSITIVE),
        'k': POSITIVE,
        'min_threshold': NON_NEGATIVE,
        'morph_size': NON_NEGATIVE_INTEGER,
    }

    def __init__(self, threshold='auto', k=5.0, min_threshold=0.1, morph_size=3):
        self.threshold = threshold
        self.k = k
        self.min_threshold = min_threshold
        self.morph_size = morph_size

    def validate(self):
        """Raise ``ValueError`` for an unusable parameter; return self."""
        return validate_params(self)

    def estimate_threshold(self, residual, frames=None):
        """
        Return the threshold ``tau`` for a window.

        Parameters
        ----------
        residual : ndarray (..., n, m)
            ``D - L`` of the window.
        frames : ndarray (..., n, m) or None
            The window ``D`` itself; bounds the noise estimate by that of the
            consecutive-frame differences (see the module docstring).

        """
        if not isinstance(self.threshold, str):
            return float(self.threshold)
        sigma = robust_sigma(residual)
        if frames is not None and np.shape(frames)[-1] > 1:
            frames = np.asarray(frames)
            sigma = min(sigma, robust_sigma(np.diff(frames, axis=-1)) / np.sqrt(2.0))
        return max(float(self.min_threshold), self.k * sigma)

    def threshold_from_noise(self, noise):
        """
        Return ``tau`` from per-pixel noise levels (a model solved for a per-pixel decision).

        ``k`` times the median level, at least ``min_threshold``; a fixed
        threshold is returned as it is.
        """
        if not isinstance(self.threshold, str):
            return float(self.threshold)
        return max(float(self.min_threshold), self.k * float(np.median(noise)))

    def apply(self, magnitude, threshold, output_shape=None):
        """
        Binary mask (uint8, 0 or 255) of one frame's foreground magnitude.

        Parameters
        ----------
        magnitude : ndarray (h, w)
            Non-negative foreground magnitude at the processing size.
        threshold : float
            ``tau`` from :meth:`estimate_threshold`.
        output_shape : tuple (rows, cols) or None
            Size of the returned mask (the input frame's); None keeps (h, w).

        """
        magnitude = np.asarray(magnitude, dtype=np.float32)
        if output_shape is not None and magnitude.shape != tuple(output_shape):
            magnitude = cv2.resize(magnitude, (output_shape[1], output_shape[0]),
                                   interpolation=cv2.INTER_LINEAR)
        mask = np.where(magnitude > threshold, np.uint8(255), np.uint8(0))
        return clean_mask(mask, self.morph_size)


def clean_mask(mask, size):
    """Open (speckle) then close (holes) a 0/255 mask with a ``size`` ellipse; <= 1 is off."""
    if size <= 1:
        return mask
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size))
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel)
    return cv2.morphologyEx(mask, cv2.MORPH_CLOSE, kernel)


def overlay(rgb, mask):
    """Return an RGB image (floats in [0, 1]) as uint8 with the masked pixels tinted red."""
    tinted = np.array(rgb, dtype=np.float32)
    tinted[mask > 0] = 0.5 * tinted[mask > 0] + np.array([0.5, 0.0, 0.0], dtype=np.float32)
    return to_uint8(tinted)
