# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""A textured wall on which shapes appear: the frames the published-mask rules are tested on."""

import numpy as np


def wall_then(paint, seed, frames=50, appear=40):
    """
    Yield float32 frames (48, 96, 3) of a textured wall with noise 0.004.

    From frame ``appear`` on, ``paint(image, wall)`` draws on each frame in
    place; ``seed`` draws the wall and the noise.
    """
    rng = np.random.default_rng(seed)
    wall = rng.uniform(0.3, 0.6, (48, 96, 3)).astype(np.float32)
    for index in range(frames):
        image = wall + rng.normal(0, 0.004, wall.shape).astype(np.float32)
        if index >= appear:
            paint(image, wall)
        yield np.clip(image, 0, 1)
