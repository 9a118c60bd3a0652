# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Depth images in metres and the foreground's points in 3-D (no ROS import).

Depth follows REP 118: ``uint16`` images hold millimetres with 0 for "no
reading", ``float32`` images hold metres with NaN for "no reading" (and
+-Inf for out of range, treated as invalid here too). Points are in the depth
camera's optical frame: x right, y down, z forward, as depth_image_proc's
``point_cloud_xyz`` computes them from the pinhole matrix ``K``.
"""

from dataclasses import dataclass

import cv2
import numpy as np

#: uint16 depth unit: millimetres (REP 118).
MILLIMETRE = np.float32(1e-3)


@dataclass(frozen=True)
class PinholeIntrinsics:
    """The focal lengths and principal point of a rectified (pinhole) camera, in pixels."""

    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_k(cls, k):
        """
        Read the row-major 3 x 3 matrix ``K`` of a ``sensor_msgs/CameraInfo``.

        Raises
        ------
        ValueError
            When ``K`` does not have 9 finite entries or a focal length is not
            positive (an uncalibrated camera publishes all zeros).

        """
        k = np.asarray(k, dtype=np.float64).reshape(-1)
        if k.size != 9 or not np.all(np.isfinite(k)):
            raise ValueError(f'K must hold 9 finite numbers, got {k.size} values')
        if not (k[0] > 0 and k[4] > 0):
            raise ValueError(f'K has no positive focal lengths (fx {k[0]}, fy {k[4]}): '
                             'is the camera calibrated?')
        return cls(fx=float(k[0]), fy=float(k[4]), cx=float(k[2]), cy=float(k[5]))


def depth_in_metres(depth):
    """
    Return a depth image as float32 metres with NaN where there is no reading.

    Parameters
    ----------
    depth : ndarray (h, w), uint16 (millimetres, 0 invalid) or float32 (metres,
        NaN invalid)
        Non-finite and non-positive float depths are invalid too.

    Returns
    -------
    metres : ndarray (h, w) float32
        A new array.

    """
    depth = np.asarray(depth)
    if depth.ndim != 2:
        raise ValueError(f'expected an (h, w) depth image, got shape {depth.shape}')
    if depth.dtype == np.uint16:
        metres = depth.astype(np.float32) * MILLIMETRE
        metres[depth == 0] = np.nan
        return metres
    if depth.dtype == np.float32:
        metres = depth.copy()
        with np.errstate(invalid='ignore'):
            metres[~(np.isfinite(metres) & (metres > 0))] = np.nan
        return metres
    raise ValueError(f'depth must be uint16 (mm) or float32 (m), got {depth.dtype}')


def mask_to_shape(mask, shape):
    """
    Return ``mask`` (h, w) as a boolean mask of ``shape``.

    A depth image registered to the colour image sees the same view; when it
    has another resolution the mask is resized by nearest neighbour.
    """
    mask = np.asarray(mask)
    if mask.shape[:2] != tuple(shape[:2]):
        mask = cv2.resize(mask.astype(np.uint8), (shape[1], shape[0]),
                          interpolation=cv2.INTER_NEAREST)
    return mask.astype(bool, copy=False)


def invalidate_background(depth, mask):
    """
    Return a copy of ``depth`` with every background pixel set to "no reading".

    The encoding is kept: 0 for uint16, NaN for float32, so the result is a
    valid depth image for any REP 118 consumer (MoveIt's depth image
    occupancy updater, depth_image_proc).
    """
    depth = np.asarray(depth)
    invalid = 0 if depth.dtype.kind in 'ui' else np.nan
    out = depth.copy()
    out[~mask_to_shape(mask, depth.shape)] = invalid
    return out


def back_project(depth_m, mask, intrinsics, step=1):
    """
    Return the 3-D points of the foreground pixels with a valid depth.

    Parameters
    ----------
    depth_m : ndarray (h, w) float32
        Depth in metres, NaN invalid (see :func:`depth_in_metres`).
    mask : ndarray (h, w)
        Foreground where non-zero; resized to the depth image if needed.
    intrinsics : PinholeIntrinsics
        Of the depth image.
    step : int
        Take every ``step``-th pixel in each direction (1 = all pixels).

    Returns
    -------
    points : ndarray (n, 3) float32
        x, y, z in metres in the optical frame, rows in image order.

    """
    if int(step) < 1:
        raise ValueError(f'step must be a positive integer, got {step!r}')
    step = int(step)
    depth_m = np.asarray(depth_m, dtype=np.float32)
    selected = mask_to_shape(mask, depth_m.shape)[::step, ::step]
    sampled = depth_m[::step, ::step]
    rows, cols = np.nonzero(selected & np.isfinite(sampled))
    z = sampled[rows, cols]
    u = cols.astype(np.float32) * np.float32(step)
    v = rows.astype(np.float32) * np.float32(step)
    points = np.empty((z.size, 3), dtype=np.float32)
    points[:, 0] = (u - np.float32(intrinsics.cx)) * z / np.float32(intrinsics.fx)
    points[:, 1] = (v - np.float32(intrinsics.cy)) * z / np.float32(intrinsics.fy)
    points[:, 2] = z
    return points
