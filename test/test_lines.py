# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Blobs that are lines, not bodies, leave the published mask and only it."""

from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.streaming.lines import processing_pixels_of, without_lines
import numpy as np
import pytest
from walls import wall_then


def _mask(*boxes):
    mask = np.zeros((40, 60), np.uint8)
    for top, bottom, left, right in boxes:
        mask[top:bottom, left:right] = 255
    return mask


@pytest.mark.parametrize('width', [1, 2])
def test_a_band_one_or_two_pixels_wide_is_a_line(width):
    mask = _mask((5, 5 + width, 10, 40))
    assert not without_lines(mask, 25).any()


def test_a_body_keeps_its_thin_parts():
    # A 3 x 3 square anywhere makes the whole blob a body: an arm one pixel
    # wide joined to a trunk stays with it.
    mask = _mask((20, 30, 20, 26), (24, 25, 26, 50))
    assert np.array_equal(without_lines(mask, 25), mask)


def test_a_thin_blob_under_min_pixels_is_kept():
    # A sliver of 24 pixels: a part of a person as often as a line.
    mask = _mask((5, 6, 10, 34))
    assert np.array_equal(without_lines(mask, 25), mask)
    assert not without_lines(mask, 24).any()


def test_only_the_line_goes_and_the_input_is_left_as_it_was():
    mask = _mask((2, 3, 5, 45), (20, 30, 20, 30))
    before = mask.copy()
    kept = without_lines(mask, 25)
    assert np.array_equal(mask, before)
    assert not kept[2].any()
    assert np.array_equal(kept[20:30, 20:30], mask[20:30, 20:30])
    assert np.count_nonzero(kept) == 100


def test_zero_keeps_every_blob():
    mask = _mask((5, 6, 10, 40))
    assert without_lines(mask, 0) is mask


def test_the_size_of_an_obstacle_is_counted_in_the_cameras_pixels():
    # 100 camera pixels are 25 processing pixels of a frame processed at half
    # its size, and 8.3 of a 640 x 480 camera's frame processed at 184 x 138:
    # there a coreless blob of 9 processing pixels is an obstacle-sized line.
    assert processing_pixels_of(100, (120, 160), (240, 320)) == 25
    vga = processing_pixels_of(100, (138, 184), (480, 640))
    assert vga == pytest.approx(8.27, abs=0.01)
    assert not without_lines(_mask((5, 6, 10, 19)), vga).any()
    assert without_lines(_mask((5, 6, 10, 18)), vga).any()


def _paint_line_and_box(image, wall):
    """Draw a bright band two pixels high and a box."""
    image[10:12, 10:80] = 0.95          # one processing row, 35 long
    image[28:42, 60:76] = 0.95          # 7 x 8 processing pixels


def _wall_then_line_and_box(frames=50, appear=40):
    """Yield a textured wall; from ``appear`` on, a bright band two pixels high and a box."""
    return wall_then(_paint_line_and_box, 3, frames, appear)


@pytest.mark.parametrize('line_pixels', [100, 0])
def test_the_detector_publishes_the_box_and_not_the_line(line_pixels):
    detector = SlidingWindowDetector(line_pixels=line_pixels)
    results = [detector.process(image)[0] for image in _wall_then_line_and_box()]
    assert results[39].model_ready
    for result in results[41:]:
        assert result.mask[30:40, 62:74].all()
        line_share = result.mask[10:12, 14:76].mean() / 255
        assert line_share == (0.0 if line_pixels else 1.0)


def test_the_window_still_keeps_the_line_out():
    # What the window admits is the foreground before the line rule: the
    # band is replaced by the background, as any foreground is.
    detector = SlidingWindowDetector()
    for image in _wall_then_line_and_box(frames=45):
        detector.process(image)
    assert detector.previous_foreground_.reshape(24, 48)[5, 8:38].all()
