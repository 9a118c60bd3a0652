# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""An in-process ROS set-up: the detector node, publishers and output subscribers."""

import time

from dgmod_ros.detector_node import DetectorNode
from dgmod_ros.image_conversion import fill_image, image_to_array
import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from sensor_msgs.msg import CameraInfo, Image, PointCloud2


def _stamp(msg, stamp_ns, frame_id):
    msg.header.stamp.sec = stamp_ns // 10**9
    msg.header.stamp.nanosec = stamp_ns % 10**9
    msg.header.frame_id = frame_id
    return msg


def image_message(array, encoding, stamp_ns=0, frame_id='camera'):
    """Build a sensor_msgs/Image from an array already in ``encoding``'s layout."""
    return _stamp(fill_image(Image(), array, encoding), stamp_ns, frame_id)


def depth_array(metres, encoding):
    """Encode depth in metres (NaN invalid) as REP 118 16UC1 (mm, 0 invalid) or 32FC1."""
    if encoding == '16UC1':
        return np.where(np.isnan(metres), 0, np.rint(np.nan_to_num(metres) * 1000)).astype(
            np.uint16)
    return metres.astype(np.float32)


def depth_message(metres, encoding, stamp_ns=0, frame_id='depth_optical'):
    """Build a depth Image from metres (NaN invalid) in ``encoding`` (16UC1 or 32FC1)."""
    return image_message(depth_array(metres, encoding), encoding, stamp_ns, frame_id)


def camera_info_message(k, shape, stamp_ns=0, frame_id='depth_optical'):
    """Build a CameraInfo of a rectified pinhole camera with matrix ``k`` (9 floats)."""
    msg = CameraInfo(height=shape[0], width=shape[1], distortion_model='plumb_bob',
                     d=[0.0] * 5, k=list(k), r=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                     p=[k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0])
    return _stamp(msg, stamp_ns, frame_id)


class RecordingLogger:
    """Stands in for the node's logger; keeps the info lines and the warnings."""

    def __init__(self, logger):
        self.logger = logger
        self.infos = []
        self.warnings = []

    def info(self, text, **kwargs):
        self.infos.append(text)

    def warning(self, text, **kwargs):
        self.warnings.append(text)

    def __getattr__(self, name):
        return getattr(self.logger, name)


class DetectorHarness:
    """
    The node under test plus a client node that publishes frames and collects outputs.

    A context manager: ``with DetectorHarness(**parameters) as harness:``
    closes it however the block ends.
    """

    def __init__(self, **overrides):
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = DetectorNode(
            context=self.context,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()])
        self.client = rclpy.create_node('detector_test_client', context=self.context)
        self.publisher = self.client.create_publisher(Image, 'image', QoSProfile(depth=50))
        self.masks, self.backgrounds = [], []
        self.client.create_subscription(Image, 'foreground_mask', self.masks.append,
                                        QoSProfile(depth=1000))
        self.client.create_subscription(Image, 'background', self.backgrounds.append,
                                        QoSProfile(depth=1000))
        # Depth side (used with use_depth: true).
        self.depth_publisher = self.client.create_publisher(Image, 'depth/image_rect',
                                                            QoSProfile(depth=50))
        self.info_publisher = self.client.create_publisher(CameraInfo, 'depth/camera_info',
                                                           QoSProfile(depth=50))
        self.clouds, self.masked_depths, self.masked_infos = [], [], []
        for msg_type, topic, sink in ((PointCloud2, 'foreground_points', self.clouds),
                                      (Image, 'foreground_depth/image_rect', self.masked_depths),
                                      (CameraInfo, 'foreground_depth/camera_info',
                                       self.masked_infos)):
            self.client.create_subscription(msg_type, topic, sink.append, QoSProfile(depth=1000))
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.client)
        self.wait_for_connections()

    def wait_for_connections(self):
        """Spin until the configured node's subscriptions see the client's publishers."""
        topics = {s.topic_name for s in self.node.subscriptions}
        publishers = [p for p in (self.publisher, self.depth_publisher, self.info_publisher)
                      if p.topic_name in topics]
        assert self.spin_until(lambda: all(p.get_subscription_count() for p in publishers))

    def publisher_for(self, msg_type, topic):
        """Return a new client publisher, matched with the node's subscription."""
        publisher = self.client.create_publisher(msg_type, topic, QoSProfile(depth=50))
        assert self.spin_until(lambda: publisher.get_subscription_count() > 0)
        return publisher

    def spin_until(self, condition, timeout=10.0):
        """Spin until ``condition()`` holds; return False on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def send(self, msg, expect_mask=True, timeout=10.0, settle=False, publisher=None):
        """
        Publish one frame and wait for its mask (or for it to be counted as dropped).

        With ``settle``, also wait until a window solve the frame started has
        ended, so that what follows does not depend on the machine's speed.
        ``publisher`` (default: the raw ``image`` one) sends it.
        """
        before_masks = len(self.masks)
        before = self.node.statistics()
        handled = before['masks_out'] + before['frames_dropped']
        (publisher or self.publisher).publish(msg)
        if expect_mask:
            ok = self.spin_until(lambda: len(self.masks) > before_masks, timeout)
        else:
            ok = self.spin_until(lambda: self.node.statistics()['frames_dropped']
                                 + self.node.statistics()['masks_out'] > handled, timeout)
        assert ok, 'no answer from the detector'
        if settle:
            self.wait_for_solves()
        return self.masks[-1] if expect_mask else None

    def send_depth(self, msg, expect_cloud=True, timeout=10.0):
        """Publish one depth image; wait for its cloud, or for it to be counted."""
        before_clouds = len(self.clouds)

        def handled():
            figures = self.node.statistics()
            return figures['depth_in'] > before['depth_in']

        before = self.node.statistics()
        self.depth_publisher.publish(msg)
        if expect_cloud:
            assert self.spin_until(lambda: len(self.clouds) > before_clouds and len(
                self.masked_infos) == len(self.masked_depths) == len(self.clouds), timeout)
            return self.clouds[-1]
        assert self.spin_until(handled, timeout), 'the detector did not take the depth image'
        return None

    def send_rgbd(self, image_msg, depth_msg, timeout=10.0):
        """
        Publish a colour frame, then (once the node took it) its depth image.

        Waits for the depth image's cloud and the frame's mask (the fused
        mask is published when the depth partner comes); returns the cloud.
        """
        before_masks = len(self.masks)
        frames_in = self.node.statistics()['frames_in']
        self.publisher.publish(image_msg)
        assert self.spin_until(lambda: self.node.statistics()['frames_in'] > frames_in,
                               timeout), 'the detector did not take the frame'
        cloud = self.send_depth(depth_msg, timeout=timeout)
        assert self.spin_until(lambda: len(self.masks) > before_masks, timeout), 'no mask'
        return cloud

    def replay_rgbd(self, messages):
        """
        Send a driver's recording: ``(topic, message)`` of colour, camera info and depth.

        Colour topics end in ``color/image_raw``, camera infos in ``camera_info``,
        the rest is depth; a colour frame is sent with the depth image after it
        (:meth:`send_rgbd`). Yields ``(depth message, its cloud)``.
        """
        colour = None
        for topic, msg in messages:
            if topic.endswith('color/image_raw'):
                colour = msg
            elif topic.endswith('camera_info'):
                self.send_camera_info(msg)
            else:
                yield msg, self.send_rgbd(colour, msg)

    def send_camera_info(self, msg, timeout=10.0):
        """Publish a camera info and wait until the node holds it (or dropped it)."""
        before = self.node.statistics()['camera_info_dropped']
        self.info_publisher.publish(msg)
        assert self.spin_until(
            lambda: self.node._depth._camera_info is msg or self.node._depth._camera_info
            == msg or self.node.statistics()['camera_info_dropped'] > before, timeout)

    def wait_for_solves(self, timeout=30.0):
        """Wait until the solver thread is idle."""
        assert self.node._worker.wait_idle(timeout)

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    def close(self):
        """Stop the executor, the nodes and the context (``with DetectorHarness() as h`` does)."""
        self.executor.shutdown()
        self.node.destroy_node()
        self.client.destroy_node()
        rclpy.shutdown(context=self.context)


def mask_array(msg):
    """Return a mask message's pixels."""
    return image_to_array(msg)[0]
