# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Milliseconds per frame of the node's depth side at 640 x 480 (no ROS transport).

One paired frame: decode the depth message (16UC1 and 32FC1), metres, the masked
depth image, back-projection of the foreground (a person-sized mask, about 7% of
the view) at ``cloud_pixel_step`` 1, 2 and 4, and the PointCloud2 fields. Prints
the median of 200 repetitions; the colour frame's mask costs come from
benchmarks/bench_node.py.

Usage (repo root): PYTHONPATH=. python benchmarks/bench_depth.py
"""

from types import SimpleNamespace

from dgmod_ros.core.depth import (back_project, depth_in_metres, invalidate_background,
                                  PinholeIntrinsics)
from dgmod_ros.core.synthetic import synthetic_rgbd_scene
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


if __name__ == '__main__':
    main()
