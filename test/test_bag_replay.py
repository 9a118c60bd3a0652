# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""A rosbag2 replayed through the node gives the offline command's masks."""

from bags import write_image_bag
import cv2
from dgmod_ros import cli
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from ros_harness import DetectorHarness, mask_array
from rosbags.rosbag2 import Reader
from sensor_msgs.msg import Image
import yaml

PARAMETERS = {'window': 20, 'stride': 5, 'scale': 0.5, 'solve_mode': 'sync'}
# Full resolution with the solve capped at half size: the carried background.
CAPPED = dict(PARAMETERS, scale=1.0, solve_pixels=48 * 64)


@pytest.mark.parametrize('parameters', [PARAMETERS, CAPPED], ids=['defaults', 'capped'])
def test_bag_through_node_matches_offline_stream_masks(tmp_path, parameters):
    scene = synthetic_scene(n_frames=40, shape=(96, 128), seed=8)
    bag = write_image_bag(tmp_path / 'bag', scene.frames)

    with DetectorHarness(**parameters) as harness:
        node_masks = []
        with Reader(bag) as reader:
            for connection, _, raw in reader.messages():
                msg = deserialize_message(raw, Image)          # bytes as recorded
                node_masks.append(mask_array(harness.send(msg)))
        # Solves at 5 (installed at once), then every 5 frames, each installed
        # solve_lag = 5 frames later: the one taken at frame 35 is still in flight.
        assert harness.node.statistics()['solves'] >= 6

    params = tmp_path / 'detector.yaml'
    params.write_text(yaml.safe_dump({'/detector': {'ros__parameters': parameters}}))
    out = tmp_path / 'offline'
    assert cli.main(['separate', str(bag), '--out', str(out), '--config', str(params),
                     '--quiet']) == 0
    offline = sorted((out / 'masks').iterdir())
    assert len(offline) == len(node_masks) == 40
    for path, node_mask in zip(offline, node_masks):
        assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE), node_mask), path.name
