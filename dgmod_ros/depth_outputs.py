# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The detector's depth side: depth as a second witness, and the foreground in 3-D for planners.

Subscribes ``depth/image_rect`` (16UC1 millimetres or 32FC1 metres, REP 118,
registered to the colour image) and ``depth/camera_info``, judges every depth
image against the learnt depth background (:class:`DepthBackground`,
``depth_background``), pairs it with a colour frame's mask by stamp
(:class:`StampPairer`, within ``depth_slop``), fuses the two per pixel
(:func:`fuse_masks`: depth decides where it can tell, colour where it cannot),
and publishes with the depth image's header:

- ``foreground_points`` (PointCloud2, float32 x, y, z in the depth camera's
  optical frame; empty when nobody is there: planners take a silent source
  for a stale one),
- ``foreground_depth/image_rect`` (the depth image with the background set
  invalid) and ``foreground_depth/camera_info`` (the input camera info with
  that header), the pair MoveIt's depth image occupancy updater and
  depth_image_proc consume,

and, with ``depth_fuse_mask``, the fused mask as the colour frame's
``foreground_mask`` (the node holds the colour mask until its depth partner
comes, or publishes it at once while no depth arrives). With ``depth_only``
each depth image is judged and published alone, its mask included.

The numerical work is in :mod:`dgmod_ros.core.depth` and
:mod:`dgmod_ros.core.depth_background`.
"""

from collections import Counter
import threading
import time

import numpy as np
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import CameraInfo, Image, PointCloud2, PointField

from .core.depth import (back_project, depth_in_metres, invalidate_background, mask_to_shape,
                         PinholeIntrinsics)
from .core.depth_background import DepthBackground, fuse_masks
from .core.kernels.depth_background import compile_kernel as compile_depth_kernel
from .image_conversion import (depth_image_to_array, fill_image, ImageConversionError,
                               stamp_ns)
from .point_cloud import point_cloud_fields
from .stamp_pairing import StampPairer
from .transport import DEFAULT_SEGMENT_BYTES, LargeImageCheck

# Seconds between repeats of one kind of warning.
_WARN_PERIOD = 5.0
# A colour mask is held for its depth partner only while depth images come:
# the newest one stamped at most this many seconds before the frame (a depth
# camera at 6 frames/s and more; a stall costs masks at most this much delay).
_DEPTH_STALL_S = 0.25


def depth_background(values):
    """Return the validated :class:`DepthBackground` that the node's parameters describe."""
    return DepthBackground(**depth_background_settings(values)).validate()


def depth_background_settings(values):
    """Return the keyword arguments of the depth background for the node's parameters."""
    return {'noise_base': values['depth_noise_base'],
            'noise_quadratic': values['depth_noise_quadratic'],
            'noise_k': values['depth_noise_k'], 'absorb_frames': values['absorb_frames'],
            'learn_frames': values['depth_learn_frames'],
            'reveal_frames': values['depth_reveal_frames'],
            'change_fraction': values['depth_change_fraction']}


def _mono8(mask):
    return np.where(mask, np.uint8(255), np.uint8(0))


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
    Depth subscriptions, the depth background, stamp pairing and the outputs of one detector.

    Parameters
    ----------
    node : rclpy.lifecycle.LifecycleNode
        The detector; its subscriptions and lifecycle publishers (which
        follow its activation) are made here.
    values : dict
        The node's parameters (``depth_*``, ``cloud_pixel_step``,
        ``max_pixels``, ``absorb_frames``).
    callback_group : rclpy.callback_groups.CallbackGroup
        The image callback's (mutually exclusive) group: masks and depth
        images are paired without a lock of their own.
    publish_mask : callable
        ``publish_mask(header, mask, received)`` publishes a ``foreground_mask``
        (the node's publisher and counters); called for the masks this side
        holds (``depth_fuse_mask``) and in depth-only mode.
    on_scene_change : callable
        Called when the depth background restarted itself (the camera moved):
        the node restarts the colour window too.

    """

    def __init__(self, node, values, callback_group, publish_mask, on_scene_change):
        self._node = node
        self._publish_mask = publish_mask
        self._on_scene_change = on_scene_change
        self._lock = threading.Lock()     # the counters, read by diagnostics
        self._counts = Counter()
        self._camera_info = None
        self._intrinsics = None
        self._pairer = StampPairer(0, on_drop=self._on_unpaired)
        self._depth_only = values['depth_only']
        self._model = None
        self._newest_depth_ns = None
        self._colour_bytes = 0
        self._pair_size = LargeImageCheck()
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
        """Take new parameter values (slop, pixel step, size limit, the depth background's)."""
        self._pairer.slop_ns = int(round(values['depth_slop'] * 1e9))
        self._pairer.validate()
        self._pixel_step = values['cloud_pixel_step']
        self._max_pixels = values['max_pixels']
        if not (values['depth_background'] or self._depth_only):
            self._model = None
        elif self._model is None:
            self._model = depth_background(values)
            # Compiled (or loaded from numba's cache) now, not in the first depth callback.
            compile_depth_kernel()
        else:                             # what it learnt is kept
            for name, value in depth_background_settings(values).items():
                setattr(self._model, name, value)
            self._model.validate()
        self._fuse_mask = self._model is not None and values['depth_fuse_mask']

    def reset(self):
        """Drop the items waiting for a partner (the node was deactivated)."""
        self._account(self._pairer.clear)

    def reset_background(self):
        """Forget the learnt depth (``~/reset_background``: the camera was moved)."""
        if self._model is not None:
            self._model.reset()

    # ----------------------------------------------------------------- inputs
    def holds_mask(self, header):
        """
        Tell whether this side publishes the colour frame's mask (fused) when its depth comes.

        True with ``depth_fuse_mask`` while depth images arrive (the newest
        stamped at most 0.25 s before the frame); otherwise the node publishes
        the colour mask at once.
        """
        return (self._fuse_mask and self._newest_depth_ns is not None
                and self._newest_depth_ns >= stamp_ns(header) - _DEPTH_STALL_S * 1e9)

    def add_mask(self, header, mask, received=None, frame_bytes=0, held=False):
        """
        Offer a colour frame's mask for pairing.

        ``held``: this side publishes the mask (fused) once paired, or the
        colour mask as it is when it cannot be paired (:meth:`holds_mask`).
        ``frame_bytes``: the colour message's size, for the transport check.
        """
        self._colour_bytes = frame_bytes
        if self._fuse_mask and not held:
            self._release_held()          # depth stopped: what waits for it goes out now
        self._account(lambda: self._publish(
            self._pairer.add_primary(stamp_ns(header), (header, mask, received, held))))

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
        received = time.monotonic()
        self._count('depth_in')
        self._check_transport(len(msg.data))
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
        metres = depth_in_metres(depth)
        verdict = self._judge(metres)     # every depth image teaches the model, paired or not
        self._newest_depth_ns = stamp_ns(msg.header)
        payload = (msg.header, msg.encoding, depth, metres, verdict, info, self._intrinsics)
        if self._depth_only:
            fused = fuse_masks(verdict)
            self._publish_outputs(fused, payload)
            self._publish_mask(msg.header, _mono8(fused), received)
            return
        self._account(lambda: self._publish(
            self._pairer.add_secondary(stamp_ns(msg.header), payload)))

    def _judge(self, metres):
        if self._model is None:
            return None
        changes = self._model.scene_changes_
        verdict = self._model.update(metres)
        if self._model.scene_changes_ != changes:
            self._count('depth_scene_changes')
            self._node.get_logger().info(
                'depth behind the learnt background over '
                f'{self._model.change_fraction:.0%} of the view: camera moved? Depth '
                'background and window restarted')
            self._on_scene_change()
        return verdict

    def _check_transport(self, depth_bytes):
        colour = self._colour_bytes
        if colour > DEFAULT_SEGMENT_BYTES:
            return                        # the node warned about the colour frames alone
        what = (f'colour frames ({colour} bytes) plus their depth images ({depth_bytes} '
                f'bytes), {colour + depth_bytes} bytes together,' if colour
                else f'depth images of {depth_bytes} bytes')
        advice = self._pair_size.check(colour + depth_bytes, what)
        if advice:
            self._node.get_logger().warning(advice)

    # ----------------------------------------------------------------- outputs
    def _publish(self, pairs):
        for (header, mask, received, held), payload in pairs:
            depth = payload[2]
            colour = mask_to_shape(mask, depth.shape)
            verdict = payload[4]
            fused = colour if verdict is None else fuse_masks(verdict, colour)
            self._publish_outputs(fused, payload)
            if held:
                self._publish_mask(header, _mono8(mask_to_shape(fused, mask.shape)), received)

    def _publish_outputs(self, mask, payload):
        header, encoding, depth, metres, _, info, intrinsics = payload
        points = back_project(metres, mask, intrinsics, self._pixel_step)
        self._points_pub.publish(cloud_message(points, header))
        self._depth_pub.publish(fill_image(Image(), invalidate_background(depth, mask),
                                           encoding, header))
        info_out = CameraInfo()
        for name in CameraInfo.get_fields_and_field_types():
            setattr(info_out, name, getattr(info, name))
        info_out.header = header
        self._info_pub.publish(info_out)
        self._count('clouds_out')

    def _release_held(self):
        queue = self._pairer.primary_
        for index, (stamp, (header, mask, received, held)) in enumerate(queue):
            if held:
                self._publish_mask(header, mask, received)
                queue[index] = (stamp, (header, mask, received, False))

    def _on_unpaired(self, primary, payload):
        """Publish a held colour mask that will get no depth partner, as it is."""
        if primary and payload[3]:
            header, mask, received, _ = payload
            self._publish_mask(header, mask, received)

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
                   'camera_info_dropped': counts.get('camera_info_dropped', 0),
                   'depth_scene_changes': counts.get('depth_scene_changes', 0),
                   'depth_model_ready': self._model is not None and self._model.ready_}
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
