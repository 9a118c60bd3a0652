# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""An in-process ROS set-up: the detector node, a publisher and mask subscribers."""

import time

from dgmod_ros.detector_node import DetectorNode
from dgmod_ros.image_conversion import fill_image, image_to_array
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Image


def image_message(array, encoding, stamp_ns=0, frame_id='camera'):
    """Build a sensor_msgs/Image from an array already in ``encoding``'s layout."""
    msg = fill_image(Image(), array, encoding)
    msg.header.stamp.sec = stamp_ns // 10**9
    msg.header.stamp.nanosec = stamp_ns % 10**9
    msg.header.frame_id = frame_id
    return msg


class DetectorHarness:
    """The node under test plus a client node that publishes frames and collects outputs."""

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
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.executor.add_node(self.client)
        self.spin_until(lambda: self.publisher.get_subscription_count() > 0, 10.0)

    def spin_until(self, condition, timeout=10.0):
        """Spin until ``condition()`` holds; return False on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if condition():
                return True
            self.executor.spin_once(timeout_sec=0.02)
        return condition()

    def send(self, msg, expect_mask=True, timeout=10.0, settle=False):
        """
        Publish one frame and wait for its mask (or for it to be counted as dropped).

        With ``settle``, also wait until a window solve the frame started has
        ended, so that what follows does not depend on the machine's speed.
        """
        before_masks = len(self.masks)
        before = self.node.statistics()
        handled = before['masks_out'] + before['frames_dropped']
        self.publisher.publish(msg)
        if expect_mask:
            ok = self.spin_until(lambda: len(self.masks) > before_masks, timeout)
        else:
            ok = self.spin_until(lambda: self.node.statistics()['frames_dropped']
                                 + self.node.statistics()['masks_out'] > handled, timeout)
        assert ok, 'no answer from the detector'
        if settle:
            self.wait_for_solves()
        return self.masks[-1] if expect_mask else None

    def wait_for_solves(self, timeout=30.0):
        """Wait until the solver thread is idle."""
        assert self.node._worker.wait_idle(timeout)

    def close(self):
        self.executor.shutdown()
        self.node.destroy_node()
        self.client.destroy_node()
        rclpy.shutdown(context=self.context)


def mask_array(msg):
    """Return a mask message's pixels."""
    return image_to_array(msg)[0]
