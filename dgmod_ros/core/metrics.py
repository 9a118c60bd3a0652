# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Scores for backgrounds (RE, PSNR) and foreground masks (CDnet rules)."""

from dataclasses import dataclass

import numpy as np

#: CDnet ground-truth labels.
GT_FOREGROUND = 255
GT_BACKGROUND = 0
GT_SHADOW = 50          # scored as background
GT_OUTSIDE_ROI = 85     # not scored
GT_UNKNOWN = 170        # not scored


def relative_error(estimate, reference):
    """``RE = ||estimate - reference||_F / ||reference||_F``."""
    estimate = np.asarray(estimate, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    if estimate.shape != reference.shape:
        raise ValueError(f'shapes differ: {estimate.shape} vs {reference.shape}')
    denom = np.linalg.norm(reference)
    if denom == 0:
        raise ValueError('reference is all zeros: RE is undefined')
    return float(np.linalg.norm(estimate - reference) / denom)


def psnr(estimate, reference, peak=1.0):
    """``PSNR = 20 log10(peak / RMSE)`` in dB for images in ``[0, peak]``; inf if equal."""
    estimate = np.asarray(estimate, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    if estimate.shape != reference.shape:
        raise ValueError(f'shapes differ: {estimate.shape} vs {reference.shape}')
    rmse = np.sqrt(np.mean((estimate - reference) ** 2))
    return float('inf') if rmse == 0 else float(20.0 * np.log10(peak / rmse))


@dataclass
class ConfusionCounts:
    """
    Pixel counts summed over frames, CDnet-style.

    Ground truth 255 is foreground; 0 and 50 (hard shadow) are background;
    85 (outside the temporal ROI) and 170 (unknown band) are not scored.
    """

    tp: int = 0
    fp: int = 0
    fn: int = 0
    tn: int = 0

    def add(self, predicted, groundtruth, roi=None):
        """Accumulate one frame: ``predicted`` bool/0-255 mask, ``groundtruth`` CDnet labels."""
        predicted = np.asarray(predicted) > 0
        groundtruth = np.asarray(groundtruth)
        if predicted.shape != groundtruth.shape:
            raise ValueError(f'mask {predicted.shape} and ground truth {groundtruth.shape} differ')
        positive = groundtruth == GT_FOREGROUND
        negative = (groundtruth == GT_BACKGROUND) | (groundtruth == GT_SHADOW)
        if roi is not None:
            inside = np.asarray(roi) > 0
            positive &= inside
            negative &= inside
        self.tp += int(np.count_nonzero(predicted & positive))
        self.fn += int(np.count_nonzero(~predicted & positive))
        self.fp += int(np.count_nonzero(predicted & negative))
        self.tn += int(np.count_nonzero(~predicted & negative))
        return self

    @property
    def precision(self):
        """``TP / (TP + FP)``; 0 when nothing was predicted."""
        total = self.tp + self.fp
        return self.tp / total if total else 0.0

    @property
    def recall(self):
        """``TP / (TP + FN)``; 0 when the ground truth has no foreground."""
        total = self.tp + self.fn
        return self.tp / total if total else 0.0

    @property
    def fmeasure(self):
        """``2 Pr Re / (Pr + Re)``; 0 when both are 0."""
        p, r = self.precision, self.recall
        return 2 * p * r / (p + r) if p + r else 0.0

    def as_dict(self):
        """Return the counts and the three scores, for reports."""
        return {'tp': self.tp, 'fp': self.fp, 'fn': self.fn, 'tn': self.tn,
                'precision': self.precision, 'recall': self.recall, 'fmeasure': self.fmeasure}


def iou(predicted, truth):
    """Intersection over union of two binary masks; 1 when both are empty."""
    predicted = np.asarray(predicted) > 0
    truth = np.asarray(truth) > 0
    union = np.count_nonzero(predicted | truth)
    return 1.0 if union == 0 else np.count_nonzero(predicted & truth) / union
