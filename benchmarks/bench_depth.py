# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Milliseconds per frame of the node's depth side at 640 x 480 (no ROS transport).

One paired frame: decode the depth message (16UC1 and 32FC1), metres, the masked
depth image, back-projection of the foreground (a person-sized mask, about 7% of
the view) at ``cloud_pixel_step`` 1, 2 and 4, and the PointCloud2 fields; then the
depth background (judge and learn one noisy depth image, compiled and its numpy
reference) and the per-pixel fusion, beside the colour path's own per-frame cost
in the same run (the streaming detector's ``push`` at the defaults, no window
solve). Prints medians of 200 repetitions (100 for the colour path).

Usage (repo root): PYTHONPATH=. python benchmarks/bench_depth.py
"""

from types import SimpleNamespace

from dgmod_ros import config
from dgmod_ros.core.depth import (back_project, depth_in_metres, invalidate_background,
                                  PinholeIntrinsics)
from dgmod_ros.core.depth_background import DepthBackground, fuse_masks
from dgmod_ros.core.kernels.depth_background import compile_kernel
from dgmod_ros.core.synthetic import synthetic_rgbd_scene
from dgmod_ros.core.synthetic_depth import WalkAndStop
from dgmod_ros.core.warmup import compile_all
from dgmod_ros.image_conversion import array_to_image_fields, depth_image_to_array
from dgmod_ros.point_cloud import point_cloud_fields
import numpy as np
from timing import median_ms

REPEATS = 200


def main():
    scene = synthetic_rgbd_scene(n_frames=20, shape=(480, 640))
    index = 20 // 2                      # the person in the middle of the view
    mask = scene.masks[index] > 0
    intrinsics = PinholeIntrinsics.from_k(scene.k)
    print(f'640 x 480, foreground {mask.mean():.1%} of the view, median of {REPEATS}')
    for encoding in ('16UC1', '32FC1'):
        metres = scene.depth[index]
        raw = (np.where(np.isnan(metres), 0, np.rint(np.nan_to_num(metres) * 1000))
               .astype(np.uint16) if encoding == '16UC1' else metres)
        msg = SimpleNamespace(**array_to_image_fields(raw, encoding))
        for step in (1, 2, 4):
            def frame():
                depth = depth_image_to_array(msg)
                invalidate_background(depth, mask)
                points = back_project(depth_in_metres(depth), mask, intrinsics, step)
                point_cloud_fields(points)
                return points.shape[0]
            points = frame()
            print(f'  {encoding} cloud_pixel_step {step}: {median_ms(frame, REPEATS):6.2f} ms, '
                  f'{points} points')
    background_and_colour()


def background_and_colour():
    """Print the depth background's and the fusion's cost beside the colour path's."""
    scene = WalkAndStop(shape=(480, 640), empty_frames=30, walk_frames=20, noise_base=0.002,
                        noise_quadratic=0.005)
    frames = [scene.frame(t) for t in range(60)]
    compile_kernel()
    costs = {}
    for compiled in (True, False):
        model = DepthBackground(compiled=compiled)
        for _, depth, _ in frames[:50]:
            model.update(depth)
        index = iter(range(10**9))

        def update(model=model):
            return model.update(frames[50 + next(index) % 10][1])
        costs[compiled] = median_ms(update, REPEATS)
    verdict = update()
    colour_mask = frames[-1][2].astype(np.uint8) * 255
    fuse = median_ms(lambda: fuse_masks(verdict, colour_mask), REPEATS)
    compile_all()
    detector = config.build_detector(dict(config.DEFAULTS))
    for rgb, _, _ in frames[:40]:           # warm-up, then the solved model's fast path
        detector.process(rgb, 'rgb')
    colour_index = iter(range(10**9))
    colour = median_ms(lambda: detector.push(frames[40 + next(colour_index) % 20][0], 'rgb'),
                       REPEATS // 2)
    print(f'depth background, 640 x 480 (judge + learn one image): compiled '
          f'{costs[True]:.2f} ms, numpy reference {costs[False]:.2f} ms '
          f'({costs[False] / costs[True]:.1f}x); fusion {fuse:.2f} ms')
    print(f'colour path, 640 x 480 rgb8 (push at the defaults, no solve): {colour:.2f} ms; '
          f'depth background + fusion = {(costs[True] + fuse) / colour:.0%} of it')


if __name__ == '__main__':
    main()
