# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The built-in demo: frames replayed through the detector node, in-process.

Without an argument it renders a synthetic scene (textured room, a walking
person-sized shape, noise, slow light drift) and publishes it at 30 frames/s to
the ``detector`` node, exactly as a camera driver would. Given a folder of
frames, a video or a rosbag2, it replays that instead. Masks, backgrounds and
an overlay montage go to ``out/demo/``; accuracy (against the synthetic truth,
or a CDnet ``groundtruth/`` folder when there is one) and latency are printed.
"""

import argparse
import os
from pathlib import Path
import sys
import time

import cv2
import numpy as np

from .core.masks import overlay
from .core.metrics import ConfusionCounts, iou, psnr
from .core.preprocess import to_float_channels
from .core.runtime import keep_freed_memory
from .core.synthetic import synthetic_scene
from .image_conversion import fill_image, image_to_array, stamp_ns
from .inputs import BadInput, read_frames


def _load(source):
    """Return (RGB frames, truth masks or None, truth backgrounds or None, stems)."""
    if source is None:
        scene = synthetic_scene(n_frames=150, shape=(240, 320))
        return list(scene.frames), list(scene.masks), list(scene.backgrounds), \
            [f'{i:06d}' for i in range(150)]
    frames, stems = [], []
    for frame in read_frames(source):
        if isinstance(frame, BadInput):
            raise frame
        image = frame.image
        if image.ndim == 2:
            image = cv2.cvtColor(image, cv2.COLOR_GRAY2RGB)
        elif frame.channel_order == 'bgr':
            image = cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
        frames.append(np.ascontiguousarray(image[:, :, :3]).astype(np.uint8))
        stems.append(frame.stem)
    truth = Path(source) / 'groundtruth'
    masks = None
    if truth.is_dir():
        files = sorted(truth.iterdir())
        if len(files) == len(frames):
            masks = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in files]
    return frames, masks, None, stems


def replay(frames, rate=30.0, **parameters):
    """Publish frames to an in-process detector node; return masks, backgrounds, figures."""
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'OFF')
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from rclpy.qos import QoSProfile
    from sensor_msgs.msg import Image

    from .detector_node import DetectorNode

    context = Context()
    rclpy.init(context=context)
    node = DetectorNode(context=context, parameter_overrides=[
        Parameter(name, value=value) for name, value in parameters.items()])
    camera = rclpy.create_node('demo_camera', context=context)
    publisher = camera.create_publisher(Image, 'image', QoSProfile(depth=10))
    masks, backgrounds = {}, []

    def on_mask(msg):
        masks[stamp_ns(msg.header)] = image_to_array(msg)[0]

    def on_background(msg):
        stamp = stamp_ns(msg.header)
        backgrounds.append((stamp, image_to_array(msg)[0]))

    camera.create_subscription(Image, 'foreground_mask', on_mask, QoSProfile(depth=100))
    camera.create_subscription(Image, 'background', on_background, QoSProfile(depth=100))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.add_node(camera)
    try:
        while publisher.get_subscription_count() == 0:
            executor.spin_once(timeout_sec=0.01)
        period = 1.0 / rate
        start = time.monotonic()
        for index, frame in enumerate(frames):
            while time.monotonic() < start + index * period:
                executor.spin_once(timeout_sec=0.002)
            msg = fill_image(Image(), frame, 'rgb8')
            msg.header.stamp.sec, msg.header.stamp.nanosec = index, 0
            msg.header.frame_id = 'demo_camera'
            publisher.publish(msg)
        deadline = time.monotonic() + 10.0
        while len(masks) < len(frames) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.01)
        figures = node.statistics()
    finally:
        executor.shutdown()
        node.destroy_node()
        camera.destroy_node()
        rclpy.shutdown(context=context)
    ordered = [masks.get(i * 10**9) for i in range(len(frames))]
    return ordered, backgrounds, figures


def run(source=None, out_dir='out/demo'):
    """Replay, write the outputs, return the printed figures."""
    keep_freed_memory()
    frames, truth, true_backgrounds, stems = _load(source)
    if not frames:
        raise BadInput(f'no frames in {source}')
    masks, backgrounds, figures = replay(frames)
    out = Path(out_dir)
    for sub in ('masks', 'background'):
        (out / sub).mkdir(parents=True, exist_ok=True)
    for stem, mask in zip(stems, masks):
        if mask is not None:
            cv2.imwrite(str(out / 'masks' / f'{stem}.png'), mask)
    for stamp, background in backgrounds:
        if background.ndim == 3:
            background = cv2.cvtColor(background, cv2.COLOR_RGB2BGR)     # imwrite takes BGR
        cv2.imwrite(str(out / 'background' / f'{stems[stamp // 10**9]}.png'), background)
    picks = np.linspace(len(frames) // 5, len(frames) - 1, 5).astype(int)
    montage = [overlay(frames[i] / 255.0, masks[i]) for i in picks if masks[i] is not None]
    if montage:
        cv2.imwrite(str(out / 'overlay_montage.png'),
                    cv2.cvtColor(np.concatenate(montage, axis=1), cv2.COLOR_RGB2BGR))
    figures['frames'] = len(frames)
    figures['masks_written'] = sum(m is not None for m in masks)
    if truth is not None and true_backgrounds is not None:      # synthetic: IoU and PSNR
        warm = 30
        figures['mean_iou'] = float(np.mean([iou(m, t) for m, t in
                                             zip(masks[warm:], truth[warm:]) if m is not None]))
        # The truth is grey; a colour background (color: rgb) is compared by its luma.
        figures['background_psnr_db'] = float(np.median([
            psnr(to_float_channels(b, 'rgb', 'gray')[:, :, 0], true_backgrounds[s // 10**9])
            for s, b in backgrounds]))
    elif truth is not None:                                     # CDnet-style ground truth
        counts = ConfusionCounts()
        for mask, gt in zip(masks, truth):
            if mask is not None:
                counts.add(mask, gt)
        figures.update({k: counts.as_dict()[k] for k in ('precision', 'recall', 'fmeasure')})
    return figures


def main(argv=None):
    """Entry point of ``python -m dgmod_ros.demo``."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('input', nargs='?', help='folder of frames, video or rosbag2 '
                        '(default: the built-in synthetic scene)')
    parser.add_argument('--out', default='out/demo', help='output folder (default out/demo)')
    args = parser.parse_args(argv)
    try:
        figures = run(args.input, args.out)
    except BadInput as error:
        print(f'demo: error: {error}', file=sys.stderr)
        return 2
    source = args.input or 'synthetic 320 x 240 scene'
    frames = figures['frames']
    print(f'demo: {frames} frames of {source} replayed at 30 frames/s through '
          f'the detector node; outputs in {args.out}/')
    print(f"  masks: {figures['masks_written']} written, {figures['frames_dropped']} frames "
          f"dropped; {figures['solves']} window solves")
    if 'mean_iou' in figures:
        print(f"  accuracy: foreground IoU vs truth {figures['mean_iou']:.3f} (mean after the "
              f"first window), background PSNR {figures['background_psnr_db']:.1f} dB")
    elif 'fmeasure' in figures:
        print(f"  accuracy vs groundtruth/: F {figures['fmeasure']:.3f} (precision "
              f"{figures['precision']:.3f}, recall {figures['recall']:.3f})")
    print(f"  mask latency (receipt to publish): p50 {figures['mask_latency_p50_ms']:.1f} ms, "
          f"p95 {figures['mask_latency_p95_ms']:.1f} ms")
    return 0


if __name__ == '__main__':
    sys.exit(main())
