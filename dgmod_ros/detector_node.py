# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The ``detector`` node: a foreground mask for every camera frame.

Subscribes ``image`` (sensor_msgs/Image, sensor-data QoS) and publishes
``foreground_mask`` (mono8, 0/255, the frame's size and header),
``background`` (mono8 or rgb8 at the input size, the newest frame's header,
after every window solve), optionally ``foreground_overlay`` (rgb8), and
``/diagnostics``. All numerical work is in :mod:`dgmod_ros.core`; this module
converts messages, holds parameters and schedules solves.
"""

import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import Image

from . import config
from .core.masks import overlay
from .core.preprocess import to_float_channels, to_uint8
from .core.streaming import SolverFailure
from .image_conversion import fill_image, image_to_array, ImageConversionError
from .solve_worker import SolveWorker
from .stats import DetectorStats

# Seconds between repeats of one kind of warning.
_WARN_PERIOD = 5.0


def _descriptor(spec):
    descriptor = ParameterDescriptor(description=spec.description, read_only=spec.read_only)
    if spec.choices:
        descriptor.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    elif isinstance(spec.default, bool):
        pass
    elif isinstance(spec.default, int):
        descriptor.integer_range = [IntegerRange(from_value=spec.low, to_value=spec.high,
                                                 step=spec.step)]
    elif isinstance(spec.default, float):
        descriptor.floating_point_range = [FloatingPointRange(
            from_value=float(spec.low), to_value=float(spec.high), step=0.0)]
    return descriptor


class DetectorNode(Node):
    """ROS wiring around :mod:`dgmod_ros.core`'s streaming detector."""

    def __init__(self, **kwargs):
        super().__init__('detector', **kwargs)
        for spec in config.PARAMETERS:
            self.declare_parameter(spec.name, spec.default, _descriptor(spec))
        self._values = {spec.name: self.get_parameter(spec.name).value
                        for spec in config.PARAMETERS}
        config.validate(self._values)       # a bad parameter file stops the node here
        self._detector = config.build_detector(self._values)
        self._lock = threading.Lock()       # guards the detector between callbacks
        self._stats = DetectorStats()
        self._encoding = None
        self._worker = SolveWorker(self._solve, self._on_solved, self._on_solve_error)

        # Separate groups keep the image callback free to run beside the
        # diagnostics timer when the node is composed in a multi-threaded executor.
        images = MutuallyExclusiveCallbackGroup()
        timers = MutuallyExclusiveCallbackGroup()
        self._subscription = self.create_subscription(
            Image, 'image', self._on_image, qos_profile_sensor_data, callback_group=images,
            qos_overriding_options=QoSOverridingOptions.with_default_policies())
        outputs = QoSProfile(depth=5)
        self._mask_pub = self.create_publisher(Image, 'foreground_mask', outputs)
        self._background_pub = self.create_publisher(Image, 'background', outputs)
        self._overlay_pub = None
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 1)
        self._timer_group = timers
        self._diagnostics_timer = None
        self._apply_node_parameters()
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self.get_logger().info(
            f"detector ready: method {self._values['method']}, window "
            f"{self._values['window']}, stride {self._values['stride']}, scale "
            f"{self._values['scale']}, solve_mode {self._values['solve_mode']}")

    # ----------------------------------------------------------------- frames
    def _on_image(self, msg):
        received = time.monotonic()
        self._stats.received()
        try:
            image, order = image_to_array(msg, self._values['max_pixels'])
        except ImageConversionError as error:
            self._stats.drop(error.reason)
            self.get_logger().warning(f'dropped a frame: {error}',
                                      throttle_duration_sec=_WARN_PERIOD)
            return
        value_range = self._values['value_range'] or None
        with self._lock:
            if self._encoding is not None and msg.encoding != self._encoding:
                # Same size, other meaning (colour to depth, say): restart too.
                self._detector.reset()
                self._stats.window_reset()
                self.get_logger().info(f'encoding changed from {self._encoding} to '
                                       f'{msg.encoding}: window restarted')
            self._encoding = msg.encoding
            detector = self._detector
            try:
                if self._values['solve_mode'] == 'sync':
                    result, solved = detector.process(image, order or 'rgb', value_range)
                else:
                    result, solved = detector.push(image, order or 'rgb', value_range), None
                    if detector.solve_due():
                        self._stats.solve_due()
                        if not self._worker.busy:
                            # The job names its detector: the result is installed
                            # only there, and only in the same configuration.
                            self._worker.submit((detector, detector.snapshot()))
            except ValueError as error:
                self._stats.drop('invalid')
                self.get_logger().warning(f'dropped a frame: {error}',
                                          throttle_duration_sec=_WARN_PERIOD)
                return
            background = detector.background_image() if result.new_background else None
        self._mask_pub.publish(fill_image(Image(), result.mask, 'mono8', msg.header))
        self._stats.masked(time.monotonic() - received)
        if result.reset:
            self._stats.window_reset()
            self.get_logger().info(f'frame size or encoding changed to {msg.width} x '
                                   f'{msg.height} {msg.encoding}: window restarted')
        if result.solve_error:
            self._report_solve_error(SolverFailure(result.solve_error))
        if solved is not None:
            self._stats.solved(solved.seconds, solved.iterations, solved.info)
        if background is not None:
            self._publish_background(background, msg.header)
        if self._overlay_pub is not None:
            self._publish_overlay(image, order, value_range, result.mask, msg.header)

    # ----------------------------------------------------------------- solves
    @staticmethod
    def _solve(job):
        detector, snapshot = job
        return detector.solve(snapshot)

    def _on_solved(self, job, model):
        with self._lock:
            installed = self._detector.install(model)
        if installed:
            # The background is published with the next frame (new_background).
            self._stats.solved(model.seconds, model.iterations, model.info)
        else:
            self._stats.discarded()

    def _on_solve_error(self, job, error):
        if not self.context.ok():
            return      # shutting down: a solve that ends now has nowhere to go
        detector, _ = job
        with self._lock:
            detector.drop_warm_start()      # the detector that started it, if still running
        self._report_solve_error(error)

    def _report_solve_error(self, error):
        self._stats.failed(str(error))
        self.get_logger().warning(f'window solve failed, previous background kept: {error}',
                                  throttle_duration_sec=_WARN_PERIOD)

    def _publish_background(self, image, header):
        pixels = to_uint8(image)
        if pixels.shape[2] == 1:
            pixels = pixels[:, :, 0]
        encoding = 'mono8' if pixels.ndim == 2 else 'rgb8'
        self._background_pub.publish(fill_image(Image(), pixels, encoding, header))

    def _publish_overlay(self, image, order, value_range, mask, header):
        pixels = overlay(to_float_channels(image, order or 'rgb', 'rgb', value_range), mask)
        self._overlay_pub.publish(fill_image(Image(), pixels, 'rgb8', header))

    # ----------------------------------------------------------------- parameters
    def _check_parameters(self, parameters):
        candidate = dict(self._values)
        candidate.update({p.name: p.value for p in parameters})
        try:
            config.validate(candidate)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        changed = {p.name: p.value for p in parameters}
        values = dict(self._values)
        values.update(changed)
        with self._lock:
            self._detector = config.update_detector(self._detector, values, self._values)
            self._values = values
        self._apply_node_parameters()
        self.get_logger().info('parameters changed: ' + ', '.join(
            f'{name}={value}' for name, value in sorted(changed.items())))

    def _apply_node_parameters(self):
        if self._values['publish_overlay'] and self._overlay_pub is None:
            self._overlay_pub = self.create_publisher(Image, 'foreground_overlay',
                                                      QoSProfile(depth=5))
        elif not self._values['publish_overlay'] and self._overlay_pub is not None:
            self.destroy_publisher(self._overlay_pub)
            self._overlay_pub = None
        period = self._values['diagnostics_period']
        if self._diagnostics_timer is None or \
                abs(self._diagnostics_timer.timer_period_ns - period * 1e9) > 1:
            if self._diagnostics_timer is not None:
                self.destroy_timer(self._diagnostics_timer)
            self._diagnostics_timer = self.create_timer(period, self._publish_diagnostics,
                                                        callback_group=self._timer_group)

    # ----------------------------------------------------------------- diagnostics
    def statistics(self):
        """Return the node's counters and figures as a dict."""
        figures = self._stats.snapshot()
        with self._lock:
            figures.update(self._detector.status())
        figures['worker_callback_errors'] = self._worker.callback_errors
        return figures

    def diagnostic_status(self):
        """Return the node's ``DiagnosticStatus``: WARN with the problems, else OK."""
        figures = self.statistics()
        status = DiagnosticStatus(name=f'{self.get_name()}: foreground detection',
                                  hardware_id=self.get_fully_qualified_name())
        problems = []
        if figures['frames_dropped']:
            problems.append(f"{figures['frames_dropped']} frames dropped")
        if figures['solve_failures']:
            problems.append(f"{figures['solve_failures']} solves failed")
        if not figures['model_ready']:
            problems.append('warming up: no background model yet')
        timeout = self._values['solve_timeout']
        if self._stats.solve_overdue(timeout):
            problems.append(f"no window solve finished for {figures['solve_wait_s']:.0f} s "
                            f'while frames arrive (solve_timeout {timeout} s): the '
                            'background is frozen')
        status.level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
        status.message = '; '.join(problems) or 'masks published for every frame'
        status.values = [KeyValue(key=key, value=str(value)) for key, value in figures.items()]
        return status

    def _publish_diagnostics(self):
        array = DiagnosticArray(status=[self.diagnostic_status()])
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(array)

    def destroy_node(self):
        """Stop the solver thread, then the node."""
        self._worker.stop(timeout=1.0)
        return super().destroy_node()


def main(args=None):
    """Run the detector until Ctrl-C, SIGTERM or an external shutdown."""
    # Jazzy's rclpy.init() returns None (the context-manager form arrived after
    # Jazzy), so the context is shut down in a finally block instead.
    rclpy.init(args=args)
    node = None
    try:
        node = DetectorNode()
        # The solves run in the node's own thread, so the executor only carries
        # short callbacks. rclpy's MultiThreadedExecutor lost frames of a
        # 30 frames/s replay here (queue overflow during its stalls; rclpy#1452,
        # #1223; figures in docs/node.md); the single-threaded one lost none.
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
