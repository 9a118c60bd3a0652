# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The ``detector`` node: a foreground mask for every camera frame.

Subscribes ``image`` (sensor_msgs/Image, sensor-data QoS; or
``image/compressed`` with ``input_transport: compressed``) and publishes
``foreground_mask`` (mono8, 0/255, the frame's size and header),
``background`` (mono8 or rgb8 at the input size, the newest frame's header,
after every window solve), optionally ``foreground_overlay`` (rgb8), with
``use_depth`` the foreground in 3-D (:mod:`dgmod_ros.depth_outputs`), and
``/diagnostics``. Offers ``~/reset_background`` (std_srvs/Trigger).

A lifecycle node: parameters are declared at construction; configure builds
the detector, subscriptions and (lifecycle) publishers, activate starts
masking, deactivate stops it, cleanup releases it all. ``autostart`` (the
default) configures and activates at once. All numerical work is in
:mod:`dgmod_ros.core`; this module converts messages, holds parameters and
schedules solves.
"""

from functools import partial
import sys
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, TransitionCallbackReturn
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import CompressedImage, Image
from std_srvs.srv import Trigger

from . import config, health, node_parameters
from .core.masks import overlay
from .core.preprocess import to_float_channels
from .core.runtime import keep_freed_memory
from .core.streaming import SolverFailure
from .depth_outputs import DepthOutputs
from .detector_rules import EncodingWatch, mask_frame, solve_job, solve_thread_settings
from .image_conversion import (background_fields, compressed_image_to_array, fill_image,
                               image_to_array, ImageConversionError, stamp_ns)
from .solve_worker import SolveWorker
from .stats import DetectorStats
from .transport import LargeImageCheck

# Seconds between repeats of one kind of warning.
_WARN_PERIOD = 5.0


def _descriptor(spec):
    descriptor = ParameterDescriptor(description=config.describe(spec, config.NODE_ONLY),
                                     read_only=spec.read_only)
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


class StartupError(RuntimeError):
    """autostart could not configure or activate the node (the reason was logged)."""


class DetectorNode(LifecycleNode):
    """ROS wiring around :mod:`dgmod_ros.core`'s streaming detector, as a lifecycle node."""

    def __init__(self, kernel_compile=None, **kwargs):
        super().__init__('detector', **kwargs)
        # A compile of the kernels main() started before its imports, if the
        # cache was cold (core.kernel_cache): configure waits for it.
        self._kernel_compile = kernel_compile
        # Only what the node reads; the offline-only ones (max_iter) keep their defaults.
        self._values = dict(config.DEFAULTS)
        for spec in config.reads(config.NODE):
            self.declare_parameter(spec.name, spec.default, _descriptor(spec))
            self._values[spec.name] = self.get_parameter(spec.name).value
        config.validate(self._values)       # a bad parameter file stops the node here
        self._warn(node_parameters.inert_warnings(
            self._values, node_parameters.set_by_user(self._values)))
        self._warn(node_parameters.not_node_warnings(     # rclpy keeps the overrides
            getattr(self, '_parameter_overrides', {}), self.has_parameter, self._values))
        self._lock = threading.Lock()       # guards the detector between callbacks
        self._stats = DetectorStats()
        self._detector = None               # built by configure
        self._worker = None
        self._active = False
        self._lifecycle_state = 'unconfigured'
        self._large_images = LargeImageCheck()
        self._encoding = EncodingWatch()
        self._frames_ignored = 0
        self._foreground = health.ForegroundWatch()
        self._subscription = None
        self._mask_pub = self._background_pub = self._overlay_pub = None
        self._depth = None

        # Separate groups keep the image callback free to run beside the
        # diagnostics timer when the node is composed in a multi-threaded executor.
        self._image_group = MutuallyExclusiveCallbackGroup()
        self._timer_group = MutuallyExclusiveCallbackGroup()
        # Diagnostics report in every lifecycle state, so a plain publisher.
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 1)
        self._diagnostics_timer = None
        self._apply_node_parameters()
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._reset_service = self.create_service(Trigger, '~/reset_background',
                                                  self._on_reset_background)
        if self._values['autostart']:
            for transition in (self.trigger_configure, self.trigger_activate):
                if transition() != TransitionCallbackReturn.SUCCESS:
                    raise StartupError(f'autostart: {transition.__name__} failed')

    # ----------------------------------------------------------------- lifecycle
    def on_configure(self, state):
        """Build the detector, the solver thread, subscriptions and publishers."""
        try:
            detector = config.build_detector(self._values)
        except ValueError as error:
            self.get_logger().error(f'configure failed: {error}')
            return TransitionCallbackReturn.FAILURE
        # Before the first frame, not in its callback; a cold cache is filled
        # by a child process while this thread waits, stoppable (docs/node.md).
        pending, self._kernel_compile = self._kernel_compile, None
        config.load_kernels(self._values, self.get_logger().info, pending,
                            should_stop=lambda: not self.context.ok())
        keep_freed_memory()     # the solves' large temporaries reused, not mapped afresh
        with self._lock:
            self._detector = detector
            self._encoding.reset()
            self._foreground.reset()
        self._worker = SolveWorker(solve_job, self._on_solved, self._on_solve_error,
                                   initializer=partial(solve_thread_settings,
                                                       self._values['solve_threads']))
        sensor_qos = {'callback_group': self._image_group, 'qos_overriding_options':
                      QoSOverridingOptions.with_default_policies()}
        if self._values['depth_only']:
            self._subscription = None           # depth images are the input
        elif self._values['input_transport'] == 'compressed':
            self._subscription = self.create_subscription(
                CompressedImage, 'image/compressed', self._on_compressed_image,
                qos_profile_sensor_data, **sensor_qos)
        else:
            self._subscription = self.create_subscription(
                Image, 'image', self._on_image, qos_profile_sensor_data, **sensor_qos)
        outputs = QoSProfile(depth=5)
        self._mask_pub = self.create_lifecycle_publisher(Image, 'foreground_mask', outputs)
        self._background_pub = self.create_lifecycle_publisher(Image, 'background', outputs)
        if self._values['use_depth'] or self._values['depth_only']:
            self._depth = DepthOutputs(self, self._values, self._image_group,
                                       self._publish_mask, self._on_depth_scene_change)
        self._apply_node_parameters()
        self._lifecycle_state = 'inactive'
        self.get_logger().info(node_parameters.configured_line(
            self._values, self._subscription and self._subscription.topic_name, self._depth))
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state):
        """Activate the publishers and start masking frames."""
        result = super().on_activate(state)
        if result == TransitionCallbackReturn.SUCCESS:
            if self._depth is not None:
                self._depth.active = True
            self._active = True
            self._lifecycle_state = 'active'
            self.get_logger().info('detector ready: masking frames')
        return result

    def on_deactivate(self, state):
        """Stop masking (incoming frames are ignored) and deactivate the publishers."""
        self._active = False
        self._lifecycle_state = 'inactive'
        with self._lock:
            if self._depth is not None:
                self._depth.active = False
                self._depth.reset()
        return super().on_deactivate(state)

    def on_cleanup(self, state):
        """Release the detector, the solver thread, subscriptions and publishers."""
        self._release()
        self._lifecycle_state = 'unconfigured'
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state):
        """Release everything, from any state."""
        self._active = False
        self._release()
        self._lifecycle_state = 'finalized'
        return TransitionCallbackReturn.SUCCESS

    def _release(self):
        if self._worker is not None:
            self._worker.stop(timeout=1.0)
            self._worker = None
        if self._subscription is not None:
            self.destroy_subscription(self._subscription)
            self._subscription = None
        for publisher in (self._mask_pub, self._background_pub, self._overlay_pub):
            if publisher is not None:
                self.destroy_lifecycle_publisher(publisher)
        self._mask_pub = self._background_pub = self._overlay_pub = None
        if self._depth is not None:
            self._depth.destroy()
            self._depth = None
        with self._lock:
            self._detector = None

    # ----------------------------------------------------------------- frames
    def _on_image(self, msg):
        self._handle_frame(msg, image_to_array, msg.encoding)

    def _on_compressed_image(self, msg):
        self._handle_frame(msg, compressed_image_to_array, msg.format)

    def _handle_frame(self, msg, convert, encoding):
        if not self._active:
            self._frames_ignored += 1   # inactive: counted apart, never masked
            return
        received = time.monotonic()
        stamp = 1e-9 * stamp_ns(msg.header)
        self._stats.received(stamp or None)     # an unset (zero) stamp says nothing
        advice = self._large_images.check(len(msg.data))
        if advice:
            self.get_logger().warning(advice)
        try:
            image, order = convert(msg, self._values['max_pixels'])
        except ImageConversionError as error:
            self._stats.drop(error.reason)
            self.get_logger().warning(f'dropped a frame: {error}',
                                      throttle_duration_sec=_WARN_PERIOD)
            return
        value_range = self._values['value_range'] or None
        with self._lock:
            previous = self._encoding.changed(encoding)
            if previous is not None:
                self._detector.reset()
                self._stats.window_reset()
                self.get_logger().info(f'encoding changed from {previous} to '
                                       f'{encoding}: window restarted')
            detector = self._detector
            try:
                result, solved = mask_frame(detector, image, order or 'rgb', value_range,
                                            self._values['solve_mode'], self._worker,
                                            self._stats.solve_due)
            except ValueError as error:
                self._stats.drop('invalid')
                self.get_logger().warning(f'dropped a frame: {error}',
                                          throttle_duration_sec=_WARN_PERIOD)
                return
            background = detector.background_image() if result.new_background else None
            if result.frame_id == 0:        # the first frame of a size or encoding
                self.get_logger().info(node_parameters.processing_line(
                    image.shape, encoding, detector.processing_size(), self._values))
        depth = self._depth
        held = depth is not None and depth.holds_mask(msg.header)
        if depth is not None:       # first: it may release masks held before this one
            depth.add_mask(msg.header, result.mask, received, len(msg.data), held)
        if not held:                # else published fused when its depth image comes
            self._publish_mask(msg.header, result.mask, received)
        if result.reset:
            self._stats.window_reset()
            self.get_logger().info(f'frame size or encoding changed to {image.shape[1]} x '
                                   f'{image.shape[0]} {encoding}: window restarted')
        if result.solve_error:
            self._report_solve_error(SolverFailure(result.solve_error))
        if solved is not None:
            self._stats.solved(solved.seconds, solved.iterations, solved.info)
        if background is not None:
            self._publish_background(background, msg.header)
        if self._overlay_pub is not None:
            self._publish_overlay(image, order, value_range, result.mask, msg.header)

    def _publish_mask(self, header, mask, received):
        self._mask_pub.publish(fill_image(Image(), mask, 'mono8', header))
        self._stats.masked(time.monotonic() - received)
        jump = self._foreground.observe(mask, self._values['foreground_jump'])
        if jump is not None:
            self.get_logger().warning(health.jump_warning(*jump),
                                      throttle_duration_sec=_WARN_PERIOD)

    def _on_depth_scene_change(self):
        """Restart the window: the depth background restarted (the camera moved)."""
        with self._lock:
            if self._detector is not None:
                self._detector.reset()
            self._foreground.reset()
        self._stats.window_reset()

    def _on_reset_background(self, request, response):
        with self._lock:
            if self._detector is None:
                response.success = False
                response.message = f'not configured (state {self._lifecycle_state})'
                return response
            self._detector.reset()
            self._foreground.reset()
            if self._depth is not None:
                self._depth.reset_background()
        self._stats.window_reset()
        self.get_logger().info('window restarted on request')
        response.success = True
        response.message = 'window restarted: a new background is learnt from the next frames'
        return response

    # ----------------------------------------------------------------- solves
    def _on_solved(self, job, model):
        with self._lock:
            if self._detector is None:
                return      # cleaned up while the solve ran
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
        if self._background_pub is None:
            return
        self._background_pub.publish(fill_image(Image(), *background_fields(image), header))

    def _publish_overlay(self, image, order, value_range, mask, header):
        pixels = overlay(to_float_channels(image, order or 'rgb', 'rgb', value_range), mask)
        self._overlay_pub.publish(fill_image(Image(), pixels, 'rgb8', header))

    # ----------------------------------------------------------------- parameters
    def _check_parameters(self, parameters):
        # Only the table's parameters: configure declares qos_overrides.* too.
        candidate = dict(self._values, **node_parameters.table_changes(parameters))
        try:
            config.validate(candidate)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters):
        changed = node_parameters.table_changes(parameters)
        if not changed:
            return
        previous = self._values
        values = dict(previous)
        values.update(changed)
        with self._lock:
            if self._detector is not None:     # unconfigured: configure builds it
                self._detector = config.update_detector(self._detector, values, self._values)
            if self._depth is not None:
                self._depth.configure(values)
            self._values = values
        self._apply_node_parameters()
        self.get_logger().info(node_parameters.change_line(changed))
        self._warn(node_parameters.change_warnings(previous, values, changed))

    def _warn(self, lines):
        for line in lines:
            self.get_logger().warning(line)

    def _apply_node_parameters(self):
        configured = self._mask_pub is not None
        if self._values['publish_overlay'] and configured and self._overlay_pub is None:
            self._overlay_pub = self.create_lifecycle_publisher(Image, 'foreground_overlay',
                                                                QoSProfile(depth=5))
            if self._active:
                self._overlay_pub.on_activate(None)
        elif not self._values['publish_overlay'] and self._overlay_pub is not None:
            self.destroy_lifecycle_publisher(self._overlay_pub)
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
        return health.node_figures(self._stats, self._lifecycle_state, self._frames_ignored,
                                   self._foreground, self._detector_status, self._depth,
                                   self._values['depth_only'], self._worker)

    def _detector_status(self):
        with self._lock:
            return self._detector.status() if self._detector is not None else None

    def diagnostic_status(self):
        """Return the node's ``DiagnosticStatus``: WARN with the problems, else OK."""
        figures = self.statistics()
        status = DiagnosticStatus(name=f'{self.get_name()}: foreground detection',
                                  hardware_id=self.get_fully_qualified_name())
        timeout = self._values['solve_timeout']
        problems = health.problems(
            figures, self._lifecycle_state, self._stats.solve_overdue(timeout), timeout,
            self._depth.malformed() if self._depth is not None else 0,
            self._foreground.unreported(), self._values['foreground_jump'])
        status.level = DiagnosticStatus.WARN if problems else DiagnosticStatus.OK
        status.message = health.status_message(problems)
        status.values = [KeyValue(key=key, value=str(value)) for key, value in figures.items()]
        return status

    def _publish_diagnostics(self):
        array = DiagnosticArray(status=[self.diagnostic_status()])
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics_pub.publish(array)

    def destroy_node(self):
        """Stop the solver thread, then the node."""
        if self._worker is not None:
            self._worker.stop(timeout=1.0)
        return super().destroy_node()


def main(args=None, kernel_compile=None):
    """
    Run the detector until Ctrl-C, SIGTERM or an external shutdown.

    Returns the exit status: 0, or 1 when a parameter given at start-up is
    invalid (one logged error naming it and the reason, no traceback).
    ``kernel_compile``: a compile of the kernels already started
    (:mod:`dgmod_ros.detector_entry`, the installed ``detector``), ended
    with the process.
    """
    # Jazzy's rclpy.init() returns None (the context-manager form arrived after
    # Jazzy), so the context is shut down in a finally block instead.
    rclpy.init(args=args)
    node = None
    try:
        # The solves run in the node's own thread, so the executor only carries
        # short callbacks. rclpy's MultiThreadedExecutor lost frames of a
        # 30 frames/s replay here (queue overflow during its stalls; rclpy#1452,
        # #1223; figures in docs/node.md); the single-threaded one lost none.
        # Made before the node's (long) start: a Ctrl-C that lands inside an
        # executor's __init__ leaves a half-made one whose __del__ prints a
        # traceback at exit (its _sigint_gc never set).
        executor = SingleThreadedExecutor()
        try:
            node = DetectorNode(kernel_compile=kernel_compile)
        except (ParameterException, ValueError) as error:
            # Out of range or of the wrong type (rclpy), or against a
            # cross-field rule (config.validate): the messages name the parameter.
            rclpy.logging.get_logger('detector').error(
                f'invalid parameter, detector not started: {error}')
            return 1
        except StartupError:
            # The failed transition logged its reason, unless a signal
            # stopped the start (a kernel compile interrupted): a normal stop.
            return 1 if rclpy.ok() else 0
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:  # noqa: B902 - re-raised unless it is the shutdown race
        # SIGINT/SIGTERM shut the context down while a callback was
        # publishing (RCLError: publisher's context is invalid): a normal stop.
        if rclpy.ok():
            raise
    finally:
        if kernel_compile is not None:
            kernel_compile.stop()
        if node is not None:
            node.destroy_node()
        shut_down()
    return 0


def shut_down():
    """
    Shut the default context down unless a signal already did.

    ``rclpy.try_shutdown`` checks the context, then shuts it down; a SIGINT's
    handler can shut it down in between (RCLError: rcl_shutdown already
    called), which is the stop asked for, not a failure.
    """
    try:
        rclpy.try_shutdown()
    except Exception:  # noqa: B902 - rclpy's RCLError is private; re-raised unless shut down
        if rclpy.ok():
            raise


if __name__ == '__main__':
    sys.exit(main())
