# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
An RGB-D camera and a client in another process than the detector: the person in the cloud.

The camera process publishes a synthetic RGB-D scene at 30 frames/s
(sensor-data QoS, as drivers do): rgb8 colour, registered depth (16UC1 or
32FC1) and its camera info, 320 x 240 by default; a person-sized body at
1.5 m before a textured wall at 3 m, 1% of the depth pixels without a
reading, depth noise as the default noise model says. The scene: 2 s of the
wall alone, the person crossing the view ``--crossings`` times (3 s each),
walking in and standing still for ``--still`` seconds (15). The same process
subscribes ``foreground_points`` and scores every cloud against the truth of
its stamp's frame: the share of its points on the body, and the coverage
(points on the body over the body's pixels with a reading, on the
``cloud_pixel_step`` grid). The detector runs in its own process with
``use_depth:=true`` and ``--param`` overrides. Both get the package's Fast
DDS profile unless ``--no-profile``, and a ROS domain of their own.

Printed per encoding: clouds received of frames published; over the walk,
the share of clouds with a visible body (>= 20 readings) that have >= 90% of
their points on it, and the clouds with points while nobody is in view
after the first 2 s; over the still wait, the coverage per second, and its
mean and minimum over the last third.

Usage (repo root): PYTHONPATH=. python benchmarks/bench_depth_node.py
    [--encodings 16UC1,32FC1] [--param absorb_frames:=1800] [--still 15]
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import time

import numpy as np

REPO = Path(__file__).resolve().parents[1]
PROFILE = REPO / 'config' / 'fastdds_large_images.xml'
BODY_READINGS = 20       # a cloud is scored on the body once it has this many readings


def scene_from(args):
    from dgmod_ros.core.synthetic_depth import WalkAndStop
    width, height = (int(v) for v in args.size.split('x'))
    rate = args.rate
    return WalkAndStop(shape=(height, width), empty_frames=int(2 * rate),
                       walk_frames=int(1.5 * rate), crossings=args.crossings,
                       body_depth=1.5, wall_depth=3.0, invalid_fraction=0.01,
                       noise_base=0.002, noise_quadratic=0.005, seed=args.seed)


# ---------------------------------------------------------------- camera and client
def run_camera(args):
    """Publish the scene, score every cloud that comes back; print the figures as JSON."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import qos_profile_sensor_data, QoSProfile
    from sensor_msgs.msg import CameraInfo, Image, PointCloud2

    from dgmod_ros.image_conversion import fill_image
    from dgmod_ros.point_cloud import point_cloud_to_array

    scene = scene_from(args)
    frames = scene.still_from + int(args.still * args.rate)
    period_ns = int(round(1e9 / args.rate))
    base_ns = 1_000_000 * 10**9
    rclpy.init()
    node = rclpy.create_node('bench_rgbd_camera')
    image_pub = node.create_publisher(Image, 'image', qos_profile_sensor_data)
    depth_pub = node.create_publisher(Image, 'depth/image_rect', qos_profile_sensor_data)
    info_pub = node.create_publisher(CameraInfo, 'depth/camera_info', qos_profile_sensor_data)
    truth = {}                          # frame -> (person, person with a reading), packed
    scores = {}                         # frame -> (points, on body, body readings on the grid)

    def on_cloud(msg):
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        index = int(round((stamp - base_ns) / period_ns))
        if index not in truth:
            return
        person, readings = (np.unpackbits(a)[:scene.shape[0] * scene.shape[1]]
                            .reshape(scene.shape).astype(bool) for a in truth[index])
        points = point_cloud_to_array(msg)
        k = scene.k
        rows = np.rint(points[:, 1] * k[4] / points[:, 2] + k[5]).astype(int)
        cols = np.rint(points[:, 0] * k[0] / points[:, 2] + k[2]).astype(int)
        inside = (rows >= 0) & (rows < scene.shape[0]) & (cols >= 0) & (cols < scene.shape[1])
        on_body = np.count_nonzero(person[rows[inside], cols[inside]])
        grid = np.count_nonzero(readings[::args.step, ::args.step])
        scores[index] = (int(points.shape[0]), int(on_body), int(grid))

    node.create_subscription(PointCloud2, 'foreground_points', on_cloud, QoSProfile(depth=50))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    info = CameraInfo(width=scene.shape[1], height=scene.shape[0],
                      distortion_model='plumb_bob', d=[0.0] * 5, k=list(scene.k),
                      r=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0])
    messages = []           # rendered ahead: the loop below only publishes and scores
    for index in range(frames):
        rgb, depth, person = scene.frame(index)
        truth[index] = (np.packbits(person), np.packbits(person & np.isfinite(depth)))
        if args.encoding == '16UC1':
            raw = np.where(np.isnan(depth), 0, np.rint(np.nan_to_num(depth) * 1000)).astype(
                np.uint16)
        else:
            raw = depth
        messages.append((fill_image(Image(), rgb, 'rgb8'),
                         fill_image(Image(), raw, args.encoding)))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (
            image_pub.get_subscription_count() and depth_pub.get_subscription_count()
            and node.count_publishers('foreground_points')):
        executor.spin_once(timeout_sec=0.05)
    start = time.monotonic()
    for index, (colour, depth_msg) in enumerate(messages):
        stamp = base_ns + index * period_ns
        for msg, frame_id in ((colour, 'color_optical'), (depth_msg, 'depth_optical'),
                              (info, 'depth_optical')):
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 10**9)
            msg.header.frame_id = frame_id
        image_pub.publish(colour)
        info_pub.publish(info)
        depth_pub.publish(depth_msg)
        messages[index] = None
        while True:                     # collect clouds until the next frame is due
            left = start + (index + 1) / args.rate - time.monotonic()
            if left <= 0:
                break
            executor.spin_once(timeout_sec=left)
    elapsed = time.monotonic() - start
    end = time.monotonic() + 2.0       # the last clouds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
    print(json.dumps({'published': frames, 'publish_rate': frames / elapsed,
                      'still_from': scene.still_from, 'empty_frames': scene.empty_frames,
                      'rate': args.rate,
                      'scores': {str(k): v for k, v in sorted(scores.items())}}), flush=True)
    node.destroy_node()
    rclpy.shutdown()


# ---------------------------------------------------------------- detector
def run_detector(args):
    """Spin the detector until depth images stop; print its statistics as JSON."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from bench_node import type_value
    from dgmod_ros.detector_node import DetectorNode

    rclpy.init()
    overrides = [Parameter('use_depth', value=True),
                 Parameter('cloud_pixel_step', value=args.step)]
    for item in args.param:
        name, value = item.split(':=')
        overrides.append(Parameter(name, value=type_value(value)))
    node = DetectorNode(parameter_overrides=overrides)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    print('ready', flush=True)
    last, changed = 0, time.monotonic()
    deadline = time.monotonic() + args.still + 600
    while time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
        count = node.statistics()['depth_in']
        if count != last:
            last, changed = count, time.monotonic()
        elif last and time.monotonic() - changed > 3.0:
            break
    figures = {k: v for k, v in node.statistics().items() if isinstance(v, (int, float))}
    print(json.dumps(figures), flush=True)
    executor.shutdown()
    node.destroy_node()
    rclpy.shutdown()


# ---------------------------------------------------------------- the run
def last_json(text):
    for line in reversed(text.splitlines()):
        if line.startswith('{'):
            return json.loads(line)
    raise RuntimeError(f'no figures in the output:\n{text[-2000:]}')


def measure(encoding, args, environ):
    """Start the detector, then the camera; return (camera figures, detector figures)."""
    script = [sys.executable, str(Path(__file__).resolve())]
    common = ['--size', args.size, '--rate', str(args.rate), '--still', str(args.still),
              '--crossings', str(args.crossings), '--step', str(args.step),
              '--seed', str(args.seed), '--encoding', encoding]
    detector = subprocess.Popen(script + ['--role', 'detector'] + common + sum(
        (['--param', p] for p in args.param), []), stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT, text=True, env=environ)
    while True:
        line = detector.stdout.readline()
        if not line or line.strip() == 'ready':
            break
    camera = subprocess.run(script + ['--role', 'camera'] + common, capture_output=True,
                            text=True, env=environ, timeout=args.still + 600)
    detector_out, _ = detector.communicate(timeout=120)
    figures = last_json(detector_out)
    figures['transport_warnings'] = [line for line in detector_out.splitlines()
                                     if 'is not set' in line]
    return last_json(camera.stdout + camera.stderr), figures


def report(encoding, camera, detector, still_seconds):
    scores = {int(k): v for k, v in camera['scores'].items()}
    published, rate = camera['published'], camera['rate']
    still_from, empty = camera['still_from'], camera['empty_frames']
    walk = [scores[i] for i in range(empty, still_from) if i in scores]
    scored = [(points, on_body) for points, on_body, grid in walk if grid >= BODY_READINGS]
    good = sum(1 for points, on_body in scored if points and on_body >= 0.9 * points)
    phantoms = sum(1 for points, on_body, grid in walk if grid == 0 and points > 0)
    still = [(i, scores[i]) for i in range(still_from, published) if i in scores]
    cover = np.array([on_body / grid for _, (_, on_body, grid) in still if grid])
    per_second = [float(np.mean(cover[s:s + int(rate)])) for s in range(0, cover.size,
                                                                        int(rate))]
    third = cover[-cover.size // 3:] if cover.size else np.array([np.nan])
    shares = np.array([on_body / points for _, (points, on_body, _) in still if points])
    print(f'  {encoding}: clouds {len(scores)} of {published} frames '
          f'(publish rate {camera["publish_rate"]:.1f}/s); detector masks_out '
          f'{detector.get("masks_out")}, clouds_out {detector.get("clouds_out")}, '
          f'depth_in {detector.get("depth_in")}, masks_without_depth '
          f'{detector.get("masks_without_depth")}, depth_dropped {detector.get("depth_dropped")}, '
          f'depth_scene_changes {detector.get("depth_scene_changes")}', flush=True)
    for line in detector['transport_warnings']:
        print(f'    detector log: {line.strip()}', flush=True)
    print(f'    walking: {good} of {len(scored)} clouds ({100 * good / max(len(scored), 1):.1f}%) '
          f'with >= 90% of their points on the body; {phantoms} clouds with points while '
          'nobody is in view', flush=True)
    print(f'    still {still_seconds:g} s: coverage per second '
          f'{" ".join(f"{c:.2f}" for c in per_second)}; last third mean {np.mean(third):.3f}, '
          f'min {np.min(third):.3f}; points on the body {np.mean(shares):.3f} '
          f'(min {np.min(shares) if shares.size else float("nan"):.3f})', flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--encodings', default='16UC1,32FC1')
    parser.add_argument('--size', default='320x240')
    parser.add_argument('--rate', type=float, default=30.0)
    parser.add_argument('--still', type=float, default=15.0, help='seconds standing still')
    parser.add_argument('--crossings', type=int, default=3)
    parser.add_argument('--step', type=int, default=2, help='cloud_pixel_step')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--param', action='append', default=[],
                        help='detector parameter name:=value (repeatable)')
    parser.add_argument('--no-profile', action='store_true')
    parser.add_argument('--role', default='bench', choices=('bench', 'camera', 'detector'))
    parser.add_argument('--encoding', default='16UC1')
    args = parser.parse_args(argv)
    if args.role == 'camera':
        return run_camera(args)
    if args.role == 'detector':
        return run_detector(args)
    environ = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), str(REPO / 'benchmarks')]))
    environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # A domain of its own: other benchmarks on the machine publish 'image' too.
    environ.setdefault('ROS_DOMAIN_ID', str(50 + os.getpid() % 50))
    if not args.no_profile:
        environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(PROFILE)
    print(f'RGB-D camera and client in one process, the detector in another; {args.size} at '
          f'{args.rate:g} frames/s; {args.crossings} crossings, still {args.still:g} s; '
          f'detector {" ".join(args.param) or "defaults"} (use_depth, cloud_pixel_step '
          f'{args.step}); FASTRTPS_DEFAULT_PROFILES_FILE='
          f"{environ.get('FASTRTPS_DEFAULT_PROFILES_FILE', '(unset)')}; "
          f'ROS_DOMAIN_ID={environ["ROS_DOMAIN_ID"]}; {os.cpu_count()} cores', flush=True)
    for encoding in args.encodings.split(','):
        camera, detector = measure(encoding, args, environ)
        report(encoding, camera, detector, args.still)


if __name__ == '__main__':
    main()
