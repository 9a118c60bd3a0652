# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The detector's depth side: the foreground in 3-D for planners.

Subscribes ``depth/image_rect`` (16UC1 millimetres or 32FC1 metres, REP 118,
registered to the colour image) and ``depth/camera_info``, pairs each depth
image with a colour frame's mask by stamp (:class:`StampPairer`, within
``depth_slop``), and publishes with the depth image's header:

- ``foreground_points`` (PointCloud2, float32 x, y, z in the depth camera's
  optical frame; empty when nobody is there: planners take a silent source
  for a stale one),
- ``foreground_depth/image_rect`` (the depth image with the background set
  invalid) and ``foreground_depth/camera_info`` (the input camera info with
  that header), the pair MoveIt's depth image occupancy updater and
  depth_image_proc consume.

The numerical work is in :mod:`dgmod_ros.core.depth`.
"""

from collections import Counter
import threading

from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField

from .core.depth import back_project, depth_in_metres, invalidate_background, PinholeIntrinsics
from .image_conversion import (depth_image_to_array, fill_image, ImageConversionError,
                               stamp_ns)
from .point_cloud import point_cloud_fields
from .stamp_pairing import StampPairer

# Seconds between repeats of one kind of warning.
_WARN_PERIOD = 5.0


def cloud_message(points, header):
    """Return a PointCloud2 of ``points`` (n, 3) with ``header``."""
    fields = point_cloud_fields(points)
    msg = PointCloud2(header=header)
    for name, value in fields.items():
        if name == 'fields':
            value = [PointField(**field) for field in value]
        setattr(msg, name, value)
    return msg


class DepthOutputs:
    """
    Depth subscriptions, stamp pairing and the 3-D outputs of one configured detector.

    Parameters
    ----------
    node : rclpy.lifecycle.LifecycleNode
        The detector; its subscriptions and lifecycle publishers (which
        follow its activation) are made here.
    values : dict
        The node's parameters (``depth_slop``, ``cloud_pixel_step``,
        ``max_pixels``).
    callback_group : rclpy.callback_groups.CallbackGroup
        The image callback's (mutually exclusive) group: masks and depth
        images are paired without a lock of their own.

    """

    def __init__(self, node, values, callback_group):
        self._node = node
        self._lock = threading.Lock()     # the counters, read by diagnostics
        self._counts = Counter()
        self._camera_info = None
        self._intrinsics = None
        self._pairer = StampPairer(0)
        self.active = False               # follows the node's activation
        self.configure(values)
        overrides = QoSOverridingOptions.with_default_policies()
        self._subscriptions = [
            node.create_subscription(Image, 'depth/image_rect', self._on_depth,
                                     qos_profile_sensor_data, callback_group=callback_group,
                                     qos_overriding_options=overrides),
            node.create_subscription(CameraInfo, 'depth/camera_info', self._on_camera_info,
                                     qos_profile_sensor_data, callback_group=callback_group,
                                     qos_overriding_options=overrides)]
        outputs = QoSProfile(depth=5)
        create = node.create_lifecycle_publisher
        self._points_pub = create(PointCloud2, 'foreground_points', outputs)
        self._depth_pub = create(Image, 'foreground_depth/image_rect', outputs)
        self._info_pub = create(CameraInfo, 'foreground_depth/camera_info', outputs)
        self.publishers = (self._points_pub, self._depth_pub, self._info_pub)

    def configure(self, values):
        """Take new parameter values (slop, pixel step, size limit)."""
        self._pairer.slop_ns = int(round(values['depth_slop'] * 1e9))
        self._pairer.validate()
        self._pixel_step = values['cloud_pixel_step']
        self._max_pixels = values['max_pixels']

    def reset(self):
        """Drop the items waiting for a partner (the node was deactivated)."""
        self._account(self._pairer.clear)

    # ----------------------------------------------------------------- inputs
    def add_mask(self, header, mask):
        """Offer a colour frame's mask (called after it was published)."""
        self._account(lambda: self._publish(
            self._pairer.add_primary(stamp_ns(header), mask)))

    def _on_camera_info(self, msg):
        try:
            intrinsics = PinholeIntrinsics.from_k(msg.k)
        except ValueError as error:
            self._count('camera_info_dropped')
            self._node.get_logger().warning(f'dropped a camera info: {error}',
                                            throttle_duration_sec=_WARN_PERIOD)
            return
        self._camera_info, self._intrinsics = msg, intrinsics

    def _on_depth(self, msg):
        if not self.active:
            return                        # as colour frames: ignored while inactive
        self._count('depth_in')
        try:
            depth = depth_image_to_array(msg, self._max_pixels)
        except ImageConversionError as error:
            self._drop(error.reason, f'dropped a depth image: {error}')
            return
        info = self._camera_info
        if info is None:
            self._drop('no_camera_info', 'dropped a depth image: no depth/camera_info yet')
            return
        if (info.width, info.height) not in ((0, 0), (msg.width, msg.height)):
            self._drop('camera_info', f'dropped a depth image: {msg.width} x {msg.height} '
                                      f'but camera info for {info.width} x {info.height}')
            return
        payload = (msg.header, msg.encoding, depth, info, self._intrinsics)
        self._account(lambda: self._publish(
            self._pairer.add_secondary(stamp_ns(msg.header), payload)))

    # ----------------------------------------------------------------- outputs
    def _publish(self, pairs):
        for mask, (header, encoding, depth, info, intrinsics) in pairs:
            points = back_project(depth_in_metres(depth), mask, intrinsics, self._pixel_step)
            self._points_pub.publish(cloud_message(points, header))
            self._depth_pub.publish(fill_image(Image(), invalidate_background(depth, mask),
                                               encoding, header))
            info_out = CameraInfo()
            for name in CameraInfo.get_fields_and_field_types():
                setattr(info_out, name, getattr(info, name))
            info_out.header = header
            self._info_pub.publish(info_out)
            self._count('clouds_out')

    # ----------------------------------------------------------------- counters
    def _account(self, action):
        """Run ``action`` and count what the pairer dropped meanwhile."""
        before = self._pairer.unpaired_primary_, self._pairer.unpaired_secondary_
        action()
        primary = self._pairer.unpaired_primary_ - before[0]
        secondary = self._pairer.unpaired_secondary_ - before[1]
        if primary > 0:
            self._count('masks_without_depth', primary)
        if secondary > 0:
            self._count('depth_dropped_unpaired', secondary)

    def _count(self, key, amount=1):
        with self._lock:
            self._counts[key] += amount

    def _drop(self, reason, message):
        self._count(f'depth_dropped_{reason}')
        self._node.get_logger().warning(message, throttle_duration_sec=_WARN_PERIOD)

    def statistics(self):
        """
        Return the depth counters.

        ``depth_in == clouds_out + depth_dropped + depth_waiting``; malformed
        depth images are counted per reason (``depth_dropped_<reason>``)
        like colour frames, unpaired ones as ``depth_dropped_unpaired``.
        """
        with self._lock:
            counts = dict(self._counts)
        dropped = {k: v for k, v in sorted(counts.items()) if k.startswith('depth_dropped_')}
        figures = {'depth_in': counts.get('depth_in', 0),
                   'clouds_out': counts.get('clouds_out', 0),
                   'depth_dropped': sum(dropped.values()),
                   'depth_waiting': len(self._pairer.secondary_),
                   'masks_without_depth': counts.get('masks_without_depth', 0),
                   'camera_info_dropped': counts.get('camera_info_dropped', 0)}
        figures.update(dropped)
        return figures

    def malformed(self):
        """Return the number of depth images and camera infos dropped as malformed."""
        figures = self.statistics()
        return (figures['depth_dropped'] - figures.get('depth_dropped_unpaired', 0)
                + figures['camera_info_dropped'])

    def destroy(self):
        """Remove the subscriptions and publishers from the node."""
        for subscription in self._subscriptions:
            self._node.destroy_subscription(subscription)
        for publisher in self.publishers:
            self._node.destroy_lifecycle_publisher(publisher)
