# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Synthetic camera scenes with exact ground truth, for the demo and the tests."""

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass
class SyntheticScene:
    """
    Frames and their truth.

    Attributes
    ----------
    frames : ndarray (m, h, w, 3) uint8, RGB
    masks : ndarray (m, h, w) uint8, 255 where the moving shape is
    backgrounds : ndarray (m, h, w) float32 in [0, 1], grey background under
        each frame's illumination

    """

    frames: np.ndarray
    masks: np.ndarray
    backgrounds: np.ndarray


def textured_background(shape, rng):
    """Draw a static grey scene in [0.15, 0.85]: smooth shading, blobs and hard edges."""
    rows, cols = shape
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float32)
    base = 0.45 + 0.12 * np.sin(xx / cols * 2.5 * np.pi) * np.cos(yy / rows * 1.5 * np.pi)
    blobs = cv2.GaussianBlur(rng.standard_normal(shape).astype(np.float32), (0, 0),
                             max(2.0, min(shape) / 30.0))
    base += 0.08 * blobs / (np.abs(blobs).max() + 1e-6)
    for _ in range(6):  # a few furniture-like rectangles with sharp edges
        r0, c0 = rng.integers(0, rows - rows // 6), rng.integers(0, cols - cols // 6)
        r1, c1 = r0 + rng.integers(rows // 10, rows // 4), c0 + rng.integers(cols // 10, cols // 4)
        base[r0:r1, c0:c1] += rng.uniform(-0.15, 0.15)
    return np.clip(base, 0.15, 0.85).astype(np.float32)


def person_mask(shape, center, height):
    """Binary mask of a person-like shape (head over an elliptic body)."""
    rows, cols = shape
    yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float32)
    cy, cx = center
    body = ((xx - cx) / (0.22 * height)) ** 2 + ((yy - cy) / (0.38 * height)) ** 2 <= 1.0
    head_y = cy - 0.5 * height
    head = (xx - cx) ** 2 + (yy - head_y) ** 2 <= (0.12 * height) ** 2
    return body | head


def synthetic_scene(n_frames=120, shape=(120, 160), noise=0.01, drift=0.08, seed=0,
                    person_value=0.1, speed=None):
    """
    Render a static textured scene, a person-sized shape walking across, noise and drift.

    Parameters
    ----------
    n_frames : int, default=120
        Number of frames.
    shape : tuple (rows, cols), default=(120, 160)
        Frame size.
    noise : float, default=0.01
        Standard deviation of white Gaussian noise on [0, 1] intensities.
    drift : float, default=0.08
        Relative brightness change over the whole sequence (slow, linear).
    seed : int, default=0
        Seed of the texture, the noise and nothing else.
    person_value : float, default=0.1
        Mean intensity of the shape (dark clothing on a mid-grey scene).
    speed : float or None
        Columns per frame; None crosses the frame in 40 frames (about 1.3 s
        at 30 frames/s, a brisk walk across a close camera's view). The shape
        leaves on the right and comes back in from the left.

    """
    rng = np.random.default_rng(seed)
    rows, cols = shape
    background = textured_background(shape, rng)
    height = 0.55 * rows
    speed = speed if speed is not None else cols / 40.0
    frames = np.empty((n_frames, rows, cols, 3), dtype=np.uint8)
    masks = np.empty((n_frames, rows, cols), dtype=np.uint8)
    backgrounds = np.empty((n_frames, rows, cols), dtype=np.float32)
    tint = np.array([1.0, 0.97, 0.92], dtype=np.float32)  # the scene is slightly warm
    margin = 0.25 * height        # half the body width: the shape leaves the frame fully
    for t in range(n_frames):  # one vectorised frame per step
        # Walks left to right, leaves the view and comes back in from the left.
        cx = (speed * t + margin) % (cols + 2 * margin) - margin
        shape_mask = person_mask(shape, (0.55 * rows, cx), height)
        light = 1.0 + drift * (t / max(n_frames - 1, 1) - 0.5)
        grey = background * light
        backgrounds[t] = grey
        grey = grey.copy()
        grey[shape_mask] = person_value + 0.03 * np.sin(np.arange(shape_mask.sum()) / 7.0)
        grey += rng.normal(0.0, noise, grey.shape).astype(np.float32)
        frames[t] = np.clip(grey[:, :, None] * tint * 255.0 + 0.5, 0, 255).astype(np.uint8)
        masks[t] = np.where(shape_mask, 255, 0)
    return SyntheticScene(frames=frames, masks=masks, backgrounds=backgrounds)


#: Height of the walking shape in metres: it is drawn as a 1.7 m person.
PERSON_HEIGHT_M = 1.7


@dataclass
class SyntheticRGBDScene(SyntheticScene):
    """
    A :class:`SyntheticScene` with a registered depth image per frame.

    Attributes
    ----------
    depth : ndarray (m, h, w) float32
        Metres: the person at ``body_depth``, the wall behind at
        ``wall_depth``, NaN where the sensor has no reading.
    k : list of 9 floats
        The row-major pinhole matrix of colour and depth (registered), with
        the focal length that makes the shape 1.7 m tall at ``body_depth``.
    body_depth, wall_depth : float

    """

    depth: np.ndarray = None
    k: list = None
    body_depth: float = 0.0
    wall_depth: float = 0.0


def synthetic_rgbd_scene(n_frames=60, shape=(120, 160), body_depth=2.0, wall_depth=4.0,
                         invalid_fraction=0.02, seed=0, **scene_options):
    """
    Render :func:`synthetic_scene` with a depth camera: a person in front of a wall.

    Parameters
    ----------
    n_frames, shape, seed, **scene_options
        As :func:`synthetic_scene`.
    body_depth, wall_depth : float
        Distances in metres along the optical axis (the wall faces the camera).
    invalid_fraction : float
        Share of pixels without a depth reading, at random (speckle, as
        structured-light and stereo sensors have).

    """
    scene = synthetic_scene(n_frames=n_frames, shape=shape, seed=seed, **scene_options)
    rows, cols = shape
    # person_mask spans from 0.62 height above its centre to 0.38 below.
    focal = 0.55 * rows * body_depth / PERSON_HEIGHT_M
    depth = np.where(scene.masks > 0, np.float32(body_depth), np.float32(wall_depth))
    rng = np.random.default_rng(seed + 1)
    depth[rng.random(depth.shape) < invalid_fraction] = np.nan
    k = [focal, 0.0, (cols - 1) / 2.0, 0.0, focal, (rows - 1) / 2.0, 0.0, 0.0, 1.0]
    return SyntheticRGBDScene(frames=scene.frames, masks=scene.masks,
                              backgrounds=scene.backgrounds, depth=depth.astype(np.float32),
                              k=k, body_depth=body_depth, wall_depth=wall_depth)
