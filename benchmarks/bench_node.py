# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Replay a camera through the detector node and print its real-time figures.

320 x 240 rgb8 frames of the synthetic scene are published at 30 frames/s
for 60 s to the node (default parameters: window 30, stride 10, half-size
processing, async solves), spun by a SingleThreadedExecutor as ``main()`` does.
Printed: frames published / received / masked / dropped, mask latency
(receipt to publish) p50 and p95, window solves per second, resident memory at
10 s and at the end. The same run with ``method:=mog2`` (OpenCV MOG2 in the
node's place) follows as the reference.

Usage (repo root): PYTHONPATH=. python benchmarks/bench_node.py [--seconds 60]
"""

import argparse
import os
import threading
import time

from dgmod_ros.core.runtime import keep_freed_memory
from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.detector_node import DetectorNode
from dgmod_ros.image_conversion import fill_image
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from sensor_msgs.msg import Image


def resident_mb():
    """Return this process's resident memory in MB (Linux)."""
    with open('/proc/self/statm') as handle:
        pages = int(handle.read().split()[1])
    return pages * os.sysconf('SC_PAGE_SIZE') / 2**20


def replay(method, seconds, rate, frames):
    """Run one replay; return the figures."""
    context = Context()
    rclpy.init(context=context)
    node = DetectorNode(context=context, parameter_overrides=[Parameter('method', value=method)])
    node_executor = SingleThreadedExecutor(context=context)     # as main() does
    node_executor.add_node(node)
    camera = rclpy.create_node('bench_camera', context=context)
    publisher = camera.create_publisher(Image, 'image', QoSProfile(depth=5))
    received = []
    camera.create_subscription(Image, 'foreground_mask', lambda m: received.append(1),
                               QoSProfile(depth=100))
    camera_executor = SingleThreadedExecutor(context=context)
    camera_executor.add_node(camera)
    threads = [threading.Thread(target=node_executor.spin, daemon=True),
               threading.Thread(target=camera_executor.spin, daemon=True)]
    for thread in threads:
        thread.start()
    while publisher.get_subscription_count() == 0:
        time.sleep(0.01)
    messages = []
    for frame in frames:
        msg = fill_image(Image(), frame, 'rgb8')
        msg.header.frame_id = 'camera'
        messages.append(msg)
    period = 1.0 / rate
    total = int(seconds * rate)
    start = time.monotonic()
    rss_10s, solves_10s = None, 0
    for index in range(total):
        target = start + index * period
        delay = target - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        msg = messages[index % len(messages)]
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = now // 10**9, now % 10**9
        publisher.publish(msg)
        if rss_10s is None and time.monotonic() - start >= 10.0:
            rss_10s = resident_mb()
            solves_10s = node.statistics()['solves']
    elapsed = time.monotonic() - start
    time.sleep(1.0)                 # let the last frames through
    figures = node.statistics()
    figures.update({'published': total, 'received_masks': len(received),
                    'rss_10s_mb': rss_10s, 'rss_end_mb': resident_mb(),
                    'solves_per_s': (figures['solves'] - solves_10s) / max(elapsed - 10.0, 1e-9),
                    'publish_rate': total / elapsed})
    node_executor.shutdown()
    camera_executor.shutdown()
    node.destroy_node()
    camera.destroy_node()
    rclpy.shutdown(context=context)
    return figures


def report(method, figures):
    lost = figures['published'] - figures['frames_in']
    print(f"{method:>6}: published {figures['published']} at "
          f"{figures['publish_rate']:.1f}/s, received {figures['frames_in']} "
          f"(lost in transport {lost}), masked {figures['masks_out']}, dropped "
          f"{figures['frames_dropped']}, masks delivered {figures['received_masks']}")
    print(f"        mask latency p50 {figures['mask_latency_p50_ms']:.1f} ms, p95 "
          f"{figures['mask_latency_p95_ms']:.1f} ms; window solves "
          f"{figures['solves']} ({figures['solves_per_s']:.2f}/s after 10 s); "
          f"RSS {figures['rss_10s_mb']:.0f} MB at 10 s, {figures['rss_end_mb']:.0f} MB at end "
          f"({100 * (figures['rss_end_mb'] / figures['rss_10s_mb'] - 1):+.1f}%)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--seconds', type=float, default=60.0)
    parser.add_argument('--rate', type=float, default=30.0)
    parser.add_argument('--methods', default='dgmod,mog2')
    args = parser.parse_args(argv)
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'OFF')
    keep_freed_memory()
    frames = synthetic_scene(n_frames=120, shape=(240, 320)).frames
    print(f'replay: 320 x 240 rgb8 at {args.rate:g} frames/s for {args.seconds:g} s, '
          f'default parameters (scale 0.5, window 30, stride 10, async), {os.cpu_count()} cores')
    for method in args.methods.split(','):
        report(method, replay(method, args.seconds, args.rate, frames))


if __name__ == '__main__':
    main()
