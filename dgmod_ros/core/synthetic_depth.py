# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
A synthetic RGB-D camera watching a person walk in and stand still, with exact truth.

For the depth background's tests and benchmarks: a textured wall, a person
who walks in from the left and stops in the middle of the view, depth noise
of the structured-light / stereo model ``noise_base + noise_quadratic * z**2``,
speckle and patches without a reading. Frames are rendered on demand, so a
minute of camera time costs no memory.
"""

from dataclasses import dataclass

import numpy as np

from .synthetic import PERSON_HEIGHT_M, person_mask, textured_background


@dataclass
class WalkAndStop:
    """
    The scene's settings; :meth:`frame` renders frame ``t``.

    Attributes
    ----------
    shape : tuple (rows, cols)
    walk_frames : int
        Frames of the walk from outside the view (left) to its middle; the
        person stands still from then on. The first ``empty_frames`` show the
        wall alone.
    empty_frames : int
    crossings : int
        Times the person first walks across the whole view (left to right,
        ``2 * walk_frames`` each) before walking in and stopping.
    body_depth, wall_depth : float
        Metres along the optical axis; the wall faces the camera.
    person_value : float or None
        Grey level of the clothes in [0, 1]; None dresses the person like the
        wall (the colour of the wall behind each pixel: colour cannot see them).
    noise_base, noise_quadratic : float
        Depth noise (m) ``noise_base + noise_quadratic * z**2``; 0, 0: exact.
    invalid_fraction : float
        Share of pixels without a reading in each frame, at random.
    invalid_patches : bool
        Also a fixed patch of the wall and the person's head without a reading
        (a black surface, hair).
    seed : int

    """

    shape: tuple = (240, 320)
    walk_frames: int = 60
    empty_frames: int = 20
    crossings: int = 0
    body_depth: float = 1.5
    wall_depth: float = 3.0
    person_value: object = 0.1
    noise_base: float = 0.0
    noise_quadratic: float = 0.0
    invalid_fraction: float = 0.01
    invalid_patches: bool = False
    seed: int = 0

    def __post_init__(self):
        rng = np.random.default_rng(self.seed)
        rows, cols = self.shape
        self._wall = textured_background(self.shape, rng)
        self.height_px = 0.55 * rows
        focal = self.height_px * self.body_depth / PERSON_HEIGHT_M
        self.k = [focal, 0.0, (cols - 1) / 2.0, 0.0, focal, (rows - 1) / 2.0, 0.0, 0.0, 1.0]
        self._patch = np.zeros(self.shape, bool)
        if self.invalid_patches:
            self._patch[rows // 10:rows // 4, cols // 10:cols // 4] = True       # on the wall
            head_y = int(0.55 * rows - 0.5 * self.height_px)
            head_r = int(0.12 * self.height_px)
            self._patch[head_y - head_r:head_y, cols // 2 - head_r:cols // 2 + head_r] = True

    def centre_column(self, t):
        """Return the column of the person's centre in frame ``t`` (None: not in view)."""
        if t < self.empty_frames:
            return None
        cols = self.shape[1]
        start, stop = -0.25 * self.height_px, (cols - 1) / 2.0
        walk = max(self.walk_frames, 1)
        t = t - self.empty_frames
        if t < 2 * walk * self.crossings:          # across, out on the right, in again
            progress = (t % (2 * walk)) / (2 * walk)
            return start + progress * (cols - 2 * start)
        progress = min(1.0, (t - 2 * walk * self.crossings) / walk)
        return start + progress * (stop - start)

    @property
    def still_from(self):
        """Return the first frame of the person standing still."""
        return self.empty_frames + self.walk_frames * (2 * self.crossings + 1)

    def frame(self, t):
        """
        Render frame ``t``.

        Returns
        -------
        rgb : ndarray (rows, cols, 3) uint8
        depth : ndarray (rows, cols) float32
            Metres, NaN without a reading.
        person : ndarray (rows, cols) bool
            Where the person is (truth).

        """
        rng = np.random.default_rng([self.seed, t])
        rows, cols = self.shape
        column = self.centre_column(t)
        person = (np.zeros(self.shape, bool) if column is None
                  else person_mask(self.shape, (0.55 * rows, column), self.height_px))
        grey = self._wall.copy()
        if self.person_value is not None:
            grey[person] = self.person_value
        grey += rng.normal(0.0, 0.01, self.shape).astype(np.float32)
        rgb = np.clip(np.repeat(grey[:, :, None], 3, axis=2) * 255.0 + 0.5, 0, 255)
        depth = np.where(person, np.float32(self.body_depth), np.float32(self.wall_depth))
        if self.noise_base or self.noise_quadratic:
            sigma = self.noise_base + self.noise_quadratic * depth * depth
            depth = depth + sigma * rng.standard_normal(self.shape).astype(np.float32)
        depth = depth.astype(np.float32)
        depth[(rng.random(self.shape) < self.invalid_fraction) | self._patch] = np.nan
        return rgb.astype(np.uint8), depth, person


def coverage(points, person, depth, k, step):
    """
    Return (share of the points on the person, share of the person's readings in the cloud).

    Parameters
    ----------
    points : ndarray (n, 3)
        The cloud (optical frame, metres).
    person, depth : ndarray (rows, cols)
        The frame's truth and depth (NaN without a reading).
    k : list of 9 floats
        The pinhole matrix.
    step : int
        The cloud's pixel step: the person's readings are counted on its grid.

    """
    rows = np.rint(points[:, 1] * k[4] / points[:, 2] + k[5]).astype(int)
    cols = np.rint(points[:, 0] * k[0] / points[:, 2] + k[2]).astype(int)
    inside = (rows >= 0) & (rows < person.shape[0]) & (cols >= 0) & (cols < person.shape[1])
    on_person = np.zeros(points.shape[0], bool)
    on_person[inside] = person[rows[inside], cols[inside]]
    readings = np.count_nonzero((person & np.isfinite(depth))[::step, ::step])
    share = float(np.mean(on_person)) if points.shape[0] else float('nan')
    return share, (np.count_nonzero(on_person) / readings if readings else float('nan'))
