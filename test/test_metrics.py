# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from dgmod_ros.core.metrics import (BackgroundPersonCounts, ConfusionCounts, iou, psnr,
                                    relative_error)
import numpy as np
import pytest


def test_confusion_counts_follow_cdnet_labels():
    truth = np.array([[255, 255, 0, 0],
                      [50, 50, 170, 85]], dtype=np.uint8)
    predicted = np.array([[255, 0, 255, 0],
                          [255, 0, 255, 255]], dtype=np.uint8)
    counts = ConfusionCounts().add(predicted, truth)
    # 255: one hit, one miss. 0 and 50 are background: two false alarms
    # (one on a plain pixel, one on a shadow), two correct rejections.
    # 170 and 85 are ignored even though predicted foreground.
    assert (counts.tp, counts.fn, counts.fp, counts.tn) == (1, 1, 2, 2)
    assert counts.precision == pytest.approx(1 / 3)
    assert counts.recall == pytest.approx(1 / 2)
    assert counts.fmeasure == pytest.approx(2 * (1 / 3) * (1 / 2) / (1 / 3 + 1 / 2))


def test_counts_sum_over_frames_not_average():
    counts = ConfusionCounts()
    counts.add(np.array([[255, 255]]), np.array([[255, 255]]))      # F = 1 alone
    counts.add(np.array([[0, 255]]), np.array([[255, 0]]))          # F = 0 alone
    assert (counts.tp, counts.fp, counts.fn) == (2, 1, 1)
    assert counts.fmeasure == pytest.approx(2 / 3)                   # not (1 + 0) / 2


def test_empty_cases_score_zero_not_nan():
    counts = ConfusionCounts().add(np.zeros((2, 2)), np.zeros((2, 2), dtype=np.uint8))
    assert counts.precision == 0.0 and counts.recall == 0.0 and counts.fmeasure == 0.0


def test_shape_mismatch_is_refused():
    with pytest.raises(ValueError, match='differ'):
        ConfusionCounts().add(np.zeros((2, 2)), np.zeros((3, 2), dtype=np.uint8))


def test_background_scores_by_hand():
    reference = np.array([[0.5, 0.5], [0.5, 0.5]])
    estimate = reference + np.array([[0.1, 0.0], [0.0, -0.1]])
    assert relative_error(estimate, reference) == pytest.approx(np.sqrt(0.02) / 1.0)
    rmse = np.sqrt(0.02 / 4)
    assert psnr(estimate, reference) == pytest.approx(20 * np.log10(1 / rmse))
    assert psnr(reference, reference) == float('inf')


def test_iou():
    a = np.array([[1, 1, 0, 0]])
    b = np.array([[0, 1, 1, 0]])
    assert iou(a, b) == pytest.approx(1 / 3)
    assert iou(np.zeros((2, 2)), np.zeros((2, 2))) == 1.0


def test_background_person_counts_score_the_places_a_person_uncovered():
    wall = np.full((40, 60, 3), 128, np.uint8)
    person = np.zeros((40, 60), np.uint8)
    person[10:30, 20:30] = 255
    clean = wall.astype(np.float32) / 255.0
    ghost = clean.copy()
    ghost[10:30, 20:30] = 0.1                       # the person left in the background
    edge = clean.copy()
    edge[:, 45] = 0.9                               # one blurred edge: no person
    away = np.zeros_like(person)
    # The opening by a 5 x 5 disc takes the ghost's corners: 0.96 of it.
    for background, expected in ((clean, 0.0), (ghost, 0.96), (edge, 0.0)):
        counts = BackgroundPersonCounts(late_frame=2)
        counts.add(0, wall, person, background)     # the person in front: nothing seen behind
        assert counts.seen == 0 and counts.late_wrong_share is None
        counts.add(1, wall, away)
        counts.add(2, wall, away)                   # the place behind seen, the newest background
        assert counts.seen == 2 * 200
        assert counts.wrong_share == pytest.approx(expected, abs=0.02)
        assert counts.late_wrong_share == pytest.approx(expected, abs=0.02)
    half = BackgroundPersonCounts()
    half.add(0, wall, person, ghost)
    half.add(1, wall, np.where(np.arange(60) < 25, 0, person).astype(np.uint8))
    assert half.seen == 100 and half.wrong_share > 0.9      # 5 columns uncovered, 5 wide
