# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The published mask's outlines are bridged and its holes filled, a body cut by one side too."""

from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.streaming.holes import closed_and_filled
import numpy as np
import pytest
from walls import wall_then


def _ring(mask, top, bottom, left, right, width=1):
    mask[top:bottom, left:right] = 255
    mask[top + width:bottom - width, left + width:right - width] = 0
    return mask


def test_what_an_outline_encloses_is_filled():
    mask = _ring(np.zeros((30, 40), np.uint8), 5, 20, 10, 30)
    before = mask.copy()
    filled = closed_and_filled(mask)
    assert np.array_equal(mask, before)
    assert filled[5:20, 10:30].all()
    assert np.count_nonzero(filled) == 15 * 20


def test_an_outline_joined_at_a_corner_only_still_encloses():
    # A diamond of single pixels, each touching the next at a corner: one
    # 8-connected blob, and its inside is no 4-connected path to the edge.
    mask = np.zeros((21, 21), np.uint8)
    for step in range(7):
        for row, col in ((10 - step, 4 + step), (10 - step, 16 - step),
                         (10 + step, 4 + step), (10 + step, 16 - step)):
            mask[row, col] = 255
    filled = closed_and_filled(mask)
    assert filled[10, 10] == 255
    assert filled[6:15, 10].all()
    assert not filled[0].any() and not filled[:, 0].any()


def test_a_body_cut_by_one_side_of_the_frame_is_closed_along_it():
    # A coat cut by the bottom edge (a U open there): its outline and that
    # edge enclose it, while the scene round it reaches the edge on three sides.
    mask = np.zeros((30, 40), np.uint8)
    mask[10:30, 10:13] = 255
    mask[10:30, 27:30] = 255
    mask[10:13, 10:30] = 255
    filled = closed_and_filled(mask)
    assert filled[10:30, 10:30].all()
    assert np.count_nonzero(filled) == 20 * 20


def test_what_reaches_a_corner_or_two_sides_is_not_closed():
    # An outline in the bottom-left corner: what it holds reaches the left
    # and the bottom side, and which side of it is the body is not known.
    mask = np.zeros((30, 40), np.uint8)
    mask[10:13, 0:20] = 255
    mask[10:30, 17:20] = 255
    filled = closed_and_filled(mask)
    assert not filled[15:30, 0:15].any()
    # A post standing in it splits its touch of the bottom side, not its reach.
    mask = np.zeros((30, 40), np.uint8)
    mask[10:13, 0:30] = 255
    mask[10:30, 27:30] = 255
    mask[20:30, 5:8] = 255
    filled = closed_and_filled(mask)
    assert not filled[14:30, 8:27].any()


def test_background_between_two_people_is_not_filled():
    mask = np.zeros((30, 40), np.uint8)
    mask[5:25, 5:12] = 255
    mask[5:25, 20:27] = 255
    assert np.array_equal(closed_and_filled(mask), mask)


def test_an_empty_mask_and_a_full_mask_are_their_own_filling():
    empty = np.zeros((10, 10), np.uint8)
    full = np.full((10, 10), 255, np.uint8)
    assert closed_and_filled(empty) is empty
    assert np.array_equal(closed_and_filled(full), full)


@pytest.mark.parametrize('gap', [1, 2, 3, 4])
def test_an_outline_opened_by_the_field_is_bridged(gap):
    # The field's 5 x 5 neighbourhood can take a thin stretch of outline
    # for noise: a gap narrower than it is bridged, and the coat inside filled.
    mask = _ring(np.zeros((30, 40), np.uint8), 5, 25, 10, 30, width=3)
    mask[5:8, 18:18 + gap] = 0
    filled = closed_and_filled(mask)
    assert filled[6:25, 10:30].all()          # a notch stays in the outer row


def test_a_gap_wider_than_the_neighbourhood_is_the_scene():
    mask = _ring(np.zeros((30, 40), np.uint8), 5, 25, 10, 30, width=3)
    mask[5:8, 17:23] = 0
    filled = closed_and_filled(mask)
    assert not filled[10:20, 14:26].any()
    assert not filled[5:8, 18:22].any()


def _paint_ring(image, wall):
    """Draw a bright ring round the wall (8 x 14 processing pixels inside)."""
    image[10:42, 40:82] = 0.95          # 16 x 21 processing pixels
    image[16:36, 46:76] = wall[16:36, 46:76]


def _wall_then_ring(frames=50, appear=40):
    """Yield a textured wall; from ``appear`` on, a bright ring round the wall."""
    return wall_then(_paint_ring, 5, frames, appear)


@pytest.mark.parametrize('fill_holes', [True, False])
def test_the_detector_publishes_the_ring_whole_or_as_it_decided(fill_holes):
    detector = SlidingWindowDetector(fill_holes=fill_holes)
    results = [detector.process(image)[0] for image in _wall_then_ring()]
    assert results[39].model_ready
    for result in results[41:]:
        assert result.mask[12:40, 42:80][:, [0, -1]].all()
        inside = result.mask[20:32, 50:72].mean() / 255
        assert inside == (1.0 if fill_holes else 0.0)


def test_the_window_keeps_the_unfilled_decision():
    # What the window admits is the decision before the fill: the wall inside
    # the ring is background there, and the next solves learn it.
    detector = SlidingWindowDetector()
    for image in _wall_then_ring(frames=45):
        detector.process(image)
    foreground = detector.previous_foreground_.reshape(24, 48)
    assert foreground[6:20, 21:40][:, [0, -1]].all()
    assert not foreground[10:16, 25:36].any()
