# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The large-image transport advice: once, only when it applies, naming the profile."""

from pathlib import Path
import xml.etree.ElementTree as ElementTree

from dgmod_ros.transport import LargeImageCheck, profile_path, PROFILE_VARIABLE
import numpy as np
from ros_harness import DetectorHarness, image_message, RecordingLogger

VGA_RGB = 640 * 480 * 3
REPO = Path(__file__).resolve().parents[1]


def test_warns_once_for_large_images_without_a_profile():
    check = LargeImageCheck(environ={})
    assert check.check(320 * 240 * 3) is None               # fits the default segment
    text = check.check(VGA_RGB)
    assert str(VGA_RGB) in text and PROFILE_VARIABLE in text
    assert str(profile_path()) in text and profile_path().is_file()
    assert check.check(VGA_RGB) is None and check.check(4 * VGA_RGB) is None
    assert check.warned_


def test_no_warning_when_the_profile_variable_is_set():
    check = LargeImageCheck(environ={PROFILE_VARIABLE: '/some/profile.xml'})
    assert check.check(4 * VGA_RGB) is None and not check.warned_


def test_the_profile_holds_five_720p_rgb_frames():
    root = ElementTree.parse(REPO / 'config' / 'fastdds_large_images.xml').getroot()
    namespace = {'p': 'http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles'}
    sizes = [int(e.text) for e in root.findall('.//p:transport_descriptor/p:segment_size',
                                               namespace)]
    assert sizes and min(sizes) >= 5 * 1280 * 720 * 3 * 1.2
    participant = root.find('.//p:participant', namespace)
    assert participant.get('is_default_profile') == 'true'


def test_the_node_warns_once_for_vga_frames(monkeypatch):
    monkeypatch.delenv(PROFILE_VARIABLE, raising=False)
    harness = DetectorHarness()
    try:
        logger = RecordingLogger(harness.node.get_logger())
        monkeypatch.setattr(harness.node, 'get_logger', lambda: logger)
        frame = np.zeros((480, 640, 3), dtype=np.uint8)
        for index in range(3):
            harness.send(image_message(frame, 'rgb8', stamp_ns=(index + 1) * 33_000_000))
        advice = [text for text in logger.warnings if PROFILE_VARIABLE in text]
        assert len(advice) == 1 and str(profile_path()) in advice[0]
        assert harness.node.statistics()['frames_in'] == 3
    finally:
        harness.close()
