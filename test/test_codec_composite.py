# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The codec composite's conditional replenishment, on made-up frames (no data)."""

from benchmark_modules import load
import cv2
import numpy as np
import pytest


@pytest.fixture(scope='module')
def codec():
    return load('codec_composite')


def _frame(rng, rows=37, cols=45):
    return rng.integers(0, 256, (rows, cols, 3), dtype=np.uint8)


def test_blocks_that_hardly_changed_are_copied_exactly_and_the_others_re_encoded(codec):
    rng = np.random.default_rng(0)
    first = codec.replenished(None, _frame(rng), 4.0, 90)
    frame = first.copy()
    frame[:, :, :] = np.clip(first.astype(np.int16) + rng.integers(-2, 3, first.shape),
                             0, 255).astype(np.uint8)     # sensor noise: mean change < 4
    frame[8:16, 16:24] = 255 - frame[8:16, 16:24]              # one block changes a lot
    written = codec.replenished(first, frame, 4.0, 90)
    moved = np.zeros(frame.shape[:2], dtype=bool)
    moved[8:16, 16:24] = True
    assert np.array_equal(written[~moved], first[~moved])
    encoded = cv2.imdecode(cv2.imencode('.jpg', frame, [cv2.IMWRITE_JPEG_QUALITY, 90])[1],
                           cv2.IMREAD_COLOR)
    assert np.array_equal(written[moved], encoded[moved])


def test_partial_blocks_at_the_edges_are_judged_by_their_own_pixels(codec):
    rng = np.random.default_rng(1)
    first = codec.replenished(None, _frame(rng), 4.0, 90)
    frame = first.copy()
    frame[32:, 40:] = 255 - frame[32:, 40:]                  # the 5 x 5 corner block
    written = codec.replenished(first, frame, 4.0, 90)
    assert not np.array_equal(written[32:, 40:], first[32:, 40:])
    assert np.array_equal(written[:32], first[:32])
    assert np.array_equal(written[32:, :40], first[32:, :40])
