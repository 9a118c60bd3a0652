# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The processing size: ``scale``, then at most ``processing_pixels`` pixels, any camera."""

from dgmod_ros import config
from dgmod_ros.core.preprocess import frame_columns, processing_shape
from dgmod_ros.core.streaming import SlidingWindowDetector
from dgmod_ros.core.subtractors import OpenCVSubtractor
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
import pytest


@pytest.mark.parametrize('frame, expected', [
    ((480, 640), (138, 184)),       # a VGA camera: capped, 25,392 pixels
    ((240, 320), (120, 160)),       # at scale 0.5 under the cap: as before
    ((288, 352), (144, 176)),       # the largest processing size of the dev sequences
    ((720, 1280), (120, 213)),      # 16:9 keeps its aspect
    ((136, 200), (68, 100)),
])
def test_frames_over_the_cap_are_scaled_down_to_it_keeping_their_aspect(frame, expected):
    shape = processing_shape(frame, 0.5, 25600)
    assert shape == expected
    assert shape[0] * shape[1] <= 25600
    assert abs(shape[1] / shape[0] - frame[1] / frame[0]) < 0.02


def test_an_exact_factor_stays_exact_and_no_cap_is_the_scale_alone():
    assert processing_shape((480, 640), 0.5, 19200) == (120, 160)
    assert processing_shape((480, 640), 0.5) == (240, 320)
    assert processing_shape((3, 5), 0.5, 1) == (1, 1)
    columns, shape = frame_columns(np.zeros((480, 640, 3), np.uint8), 0.5, 'rgb', 'rgb',
                                   None, 19200)
    assert shape == (120, 160, 3) and columns.shape == (3, 120 * 160)


@pytest.mark.parametrize('detector', [SlidingWindowDetector(),
                                      OpenCVSubtractor(color='rgb')], ids=['window', 'mog2'])
def test_a_vga_camera_is_processed_at_the_capped_size_and_masked_at_its_own(detector):
    scene = synthetic_scene(n_frames=12, shape=(480, 640), seed=2)
    for frame in scene.frames:
        result, _ = detector.process(frame)
        assert result.mask.shape == (480, 640)
    assert detector.processing_size() == (138, 184)
    assert detector.background_image().shape == (480, 640, 3)


def test_a_new_processing_size_resamples_the_window_and_an_unchanged_one_keeps_the_model():
    detector = config.build_detector(dict(config.DEFAULTS, window=12, stride=4, min_frames=4))
    scene = synthetic_scene(n_frames=16, shape=(240, 320), seed=4)
    for frame in scene.frames:
        detector.process(frame)
    model = detector.background_model_
    assert detector.shape_ == (120, 160, 3) and model is not None
    detector.configure(processing_pixels=76800)     # 160 x 120 is under it: no new size
    assert detector.shape_ == (120, 160, 3) and detector.background_model_ is model
    detector.configure(processing_pixels=4800)
    assert detector.shape_ == (60, 80, 3) and detector.background_model_ is None
    assert all(c.shape == (3, 60 * 80) for c in detector.buffer_.columns())
    result, _ = detector.process(scene.frames[0])
    assert result.mask.shape == (240, 320)
    with pytest.raises(ValueError, match='processing_pixels'):
        detector.configure(processing_pixels=0)
    assert detector.processing_pixels == 4800
