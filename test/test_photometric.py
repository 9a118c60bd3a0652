# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The lighting test of the per-pixel decision: shadows and reflections are not people."""

from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.streaming.decision import adaptive_mask
from dgmod_ros.core.streaming.kernels.photometric import distortion
from dgmod_ros.core.streaming.kernels.texture import descriptor_distance, PATTERN
from dgmod_ros.core.streaming.photometric import LightingTest
import numpy as np
import pytest

ROWS, COLS = 40, 48
NOISE = 0.01          # the pixels' noise level
K = 6.0


def _floor(seed=0):
    """Return a colour floor (3, rows, cols) of tiles: a texture of its own."""
    rng = np.random.default_rng(seed)
    tiles = np.kron(rng.uniform(0.45, 0.75, (ROWS // 8, COLS // 8)), np.ones((8, 8)))
    tint = np.array([1.0, 0.85, 0.7])[:, None, None]
    return (tint * tiles[None]).astype(np.float32)


def _region(top, left, size=12):
    region = np.zeros((ROWS, COLS), dtype=bool)
    region[top:top + size, left:left + size] = True
    return region


def _mask(frame, background, lighting, mrf_beta=0.0):
    mask, _ = adaptive_mask(frame.reshape(3, -1), background.reshape(3, -1), NOISE, K,
                            (ROWS, COLS, 3), 5, mrf_beta=mrf_beta, lighting=lighting)
    return mask > 0


def test_distortion_splits_brightness_from_chromaticity():
    background = np.array([[0.6], [0.5], [0.4]], dtype=np.float32)
    shadow = 0.6 * background
    alpha, chroma = distortion(shadow, background)
    assert alpha[0] == pytest.approx(0.6, abs=1e-6) and chroma[0] == pytest.approx(0, abs=1e-6)
    # Another colour of the same brightness (norm): alpha below 1, chromaticity changed.
    other = np.array([[0.4], [0.5], [0.6]], dtype=np.float32)
    alpha, chroma = distortion(other, background)
    assert 0.8 < alpha[0] < 1 and chroma[0] > 0.2


def test_descriptor_distance_matches_the_pattern_bit_by_bit():
    rng = np.random.default_rng(1)
    frame = rng.uniform(0, 1, (3, 9, 11)).astype(np.float32)
    background = rng.uniform(0, 1, (3, 9, 11)).astype(np.float32)
    pixels = np.array([0, 5, 4 * 11 + 5, 8 * 11 + 10])
    threshold = np.full((3, pixels.size), 0.2, dtype=np.float32)
    got = descriptor_distance(frame, background, threshold, pixels)
    padded_frame = np.pad(frame, ((0, 0), (2, 2), (2, 2)), mode='edge')
    padded_background = np.pad(background, ((0, 0), (2, 2), (2, 2)), mode='edge')
    for index, pixel in enumerate(pixels):
        row, col = divmod(int(pixel), 11)
        expected = 0
        for channel in range(3):
            reference = background[channel, row, col]
            for dr, dc in PATTERN:
                in_frame = abs(padded_frame[channel, row + 2 + dr, col + 2 + dc] - reference)
                in_background = abs(padded_background[channel, row + 2 + dr, col + 2 + dc]
                                    - reference)
                expected += (in_frame > 0.2) != (in_background > 0.2)
        assert got[index] == expected


def test_a_shadow_is_not_foreground_a_person_of_equal_brightness_is():
    background = _floor()
    frame = background.copy()
    shadow, person = _region(4, 4), _region(24, 30)
    frame[:, shadow] *= 0.7                                 # darker, same colour and texture
    # The person's colour: the floor's brightness (norm), another hue, one flat shade.
    colour = np.array([0.35, 0.5, 0.75], dtype=np.float32)
    norms = np.linalg.norm(background[:, person], axis=0)
    frame[:, person] = colour[:, None] / np.linalg.norm(colour) * norms
    plain = _mask(frame, background, None)
    # Both are changes (the median filter rounds the squares' corners).
    assert plain[shadow].mean() > 0.9 and plain[person].mean() > 0.9
    tested = _mask(frame, background, LightingTest())
    assert not tested[shadow].any()
    assert tested[person].mean() == plain[person].mean()


def test_under_the_field_light_explained_pixels_are_background_evidence():
    # The default spatial stage (the Potts field) must not pull a shadow back in.
    background = _floor()
    frame = background.copy()
    shadow, person = _region(4, 4), _region(24, 30)
    frame[:, shadow] *= 0.7
    colour = np.array([0.35, 0.5, 0.75], dtype=np.float32)
    norms = np.linalg.norm(background[:, person], axis=0)
    frame[:, person] = colour[:, None] / np.linalg.norm(colour) * norms
    plain = _mask(frame, background, None, mrf_beta=2.0)
    assert plain[shadow].mean() > 0.9 and plain[person].mean() > 0.9
    tested = _mask(frame, background, LightingTest(), mrf_beta=2.0)
    # Measured 0.11: pixels on the shadow's own outline, whose LBSP pattern the
    # outline changes, are not explained by light and the field keeps some of them.
    assert tested[shadow].mean() < 0.2
    assert tested[person].mean() > 0.9


def test_texture_tells_a_grey_person_from_a_reflection():
    background = 0.45 * _floor(2)
    frame = background.copy()
    reflection, person = _region(8, 8, 8), _region(24, 30)    # a reflection on one tile
    frame[:, reflection] *= 1.3
    # A person the floor's colour with stripes of their own: half of the pixels only a
    # little brighter than the floor (light could explain them, their texture cannot).
    stripes = np.where(np.arange(COLS) % 4 < 2, 1.2, 2.0)[None, None, :]
    frame[:, person] = (background * stripes)[:, person]
    plain = _mask(frame, background, None)
    assert plain[reflection].mean() > 0.5 and plain[person].mean() > 0.5
    tested = _mask(frame, background, LightingTest())
    assert not tested[reflection].any()
    assert tested[person].mean() == plain[person].mean()
    without_texture = _mask(frame, background, LightingTest(texture=False))
    assert without_texture[person].mean() < 0.5 * plain[person].mean()


def test_no_cue_keeps_every_candidate():
    detector = SlidingWindowDetector(chroma_cue=False, texture_cue=False).validate()
    detector.push(np.zeros((16, 16, 3), dtype=np.uint8))
    assert detector.lighting_ is None
    with pytest.raises(ValueError, match='texture_bits'):
        SlidingWindowDetector(texture_bits=49).validate()
