# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Scores for backgrounds (RE, PSNR), foreground masks (CDnet rules) and people found."""

from dataclasses import dataclass

import cv2
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


@dataclass
class PersonCounts:
    """
    The planner's view summed over frames: people found and phantom blobs.

    The rule of ``../shared/tools/object_recall.py``: a person is a connected
    component (8-neighbour) of ground truth 255 of at least ``min_area``
    pixels, found when the mask covers at least half of it; a false blob is a
    mask component of at least ``min_area`` pixels that touches no ground-truth
    foreground or unknown pixel dilated by 5 x 5.
    """

    min_area: int = 100
    people: int = 0
    found: int = 0
    false_blobs: int = 0
    frames: int = 0

    def add(self, predicted, groundtruth):
        """Accumulate one frame: ``predicted`` bool/0-255 mask, ``groundtruth`` CDnet labels."""
        predicted = np.asarray(predicted) > 0
        groundtruth = np.asarray(groundtruth)
        if predicted.shape != groundtruth.shape:
            raise ValueError(f'mask {predicted.shape} and ground truth {groundtruth.shape} differ')
        self.frames += 1
        count, labels, stats, _ = cv2.connectedComponentsWithStats(
            (groundtruth == GT_FOREGROUND).astype(np.uint8), connectivity=8)
        big = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= self.min_area) + 1
        if big.size:
            covered = np.bincount(labels[predicted], minlength=count)
            self.people += int(big.size)
            self.found += int(np.count_nonzero(
                covered[big] >= 0.5 * stats[big, cv2.CC_STAT_AREA]))
        count, labels, stats, _ = cv2.connectedComponentsWithStats(
            predicted.astype(np.uint8), connectivity=8)
        near = cv2.dilate(((groundtruth == GT_FOREGROUND) | (groundtruth == GT_UNKNOWN))
                          .astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
        touching = np.bincount(labels[near], minlength=count) > 0
        big = stats[:, cv2.CC_STAT_AREA] >= self.min_area
        big[0] = False
        self.false_blobs += int(np.count_nonzero(big & ~touching))
        return self

    @property
    def person_recall(self):
        """Share of the ground truth's people found; 0 when there were none."""
        return self.found / self.people if self.people else 0.0

    @property
    def false_blobs_per_frame(self):
        """Phantom blobs per scored frame."""
        return self.false_blobs / self.frames if self.frames else 0.0


@dataclass
class BackgroundPersonCounts:
    """
    The published background where people were: the places behind them it still gets wrong.

    A pixel's place behind a person has been seen once the ground truth has
    shown a person on it (255) and shows background (0 or a shadow) now; the
    newest published background gets it wrong where it is off the frame by
    more than ``tolerance`` (the largest channel difference on [0, 1]; 0.12
    is 30 grey levels, several times a camera's noise and well below a
    person against a wall), in patches at least ``patch`` pixels across (an
    opening by a disc): a textured edge that the upsampled background blurs
    is no person. Frames from ``late_frame`` on are counted apart as well
    (60 s at 30 frames/s: the issue's "after the first minute").
    """

    tolerance: float = 0.12
    patch: int = 5
    late_frame: int = 1800
    seen: int = 0
    wrong: int = 0
    late_seen: int = 0
    late_wrong: int = 0
    covered: np.ndarray = None
    background: np.ndarray = None

    def add(self, index, frame, groundtruth, background=None, roi=None):
        """
        Accumulate frame ``index``: ``frame`` uint8 (H, W, C) in the background's channel order.

        ``background`` float [0, 1] (H, W, C) is the one published with this
        frame, None where none was (the newest before it holds); ``roi`` bool
        (H, W) limits the pixels counted.
        """
        groundtruth = np.asarray(groundtruth)
        if self.covered is None:
            self.covered = np.zeros(groundtruth.shape, dtype=bool)
        self.covered |= groundtruth == GT_FOREGROUND
        if background is not None:
            self.background = background
        if self.background is None:
            return self
        seen = self.covered & ((groundtruth == GT_BACKGROUND) | (groundtruth == GT_SHADOW))
        if roi is not None:
            seen &= roi
        off = np.abs(np.asarray(frame, dtype=np.float32) / 255.0
                     - self.background.reshape(frame.shape)).max(axis=-1)
        disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (self.patch, self.patch))
        wrong = cv2.morphologyEx((seen & (off > self.tolerance)).astype(np.uint8),
                                 cv2.MORPH_OPEN, disc)
        seen_count, wrong_count = int(np.count_nonzero(seen)), int(np.count_nonzero(wrong))
        self.seen += seen_count
        self.wrong += wrong_count
        if index >= self.late_frame:
            self.late_seen += seen_count
            self.late_wrong += wrong_count
        return self

    @property
    def wrong_share(self):
        """Share of the seen places behind people the background got wrong; 0 when none."""
        return self.wrong / self.seen if self.seen else 0.0

    @property
    def late_wrong_share(self):
        """:attr:`wrong_share` from ``late_frame`` on; None when no frame got there."""
        return self.late_wrong / self.late_seen if self.late_seen else None
