# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The depth background's per-frame update in two compiled passes over the pixels.

:class:`~dgmod_ros.core.depth_background.DepthBackground` judges a depth
image against its model and then learns from it. In numpy that is about
thirty passes over (h, w) arrays with their temporaries (9 ms at 640 x 480
here); :func:`judge` and :func:`learn` read each pixel's state once and do
the same float32 arithmetic in the same order: the same model and verdicts,
bit for bit (``test/test_depth_background.py``). Serial and ``nogil``: the
depth callback runs beside the solve thread, whose kernels own the threads.
Importing :mod:`dgmod_ros.core.kernels` first makes its process-wide numba
settings (cache folder, threading layer) hold here too.
"""

from numba import njit
import numpy as np

# numba's cache folder and threading layer, set before the decorators below run.
from . import kernels  # noqa: F401


@njit(cache=True, nogil=True, inline='always')
def _margin(k, base, quadratic, depth):
    return k * (base + quadratic * depth * depth)


@njit(cache=True, nogil=True)
def judge(depth, background, hits, k, base, quadratic, learn_frames, verdict):
    """
    Write each pixel's verdict (0 unknown, 1 background, 2 foreground) into ``verdict``.

    All arrays are flat float32 (``verdict`` uint8). Returns the number of
    pixels judged and of those behind the model.
    """
    judged = 0
    behind = 0
    for i in range(depth.size):
        verdict[i] = 0
        d = depth[i]
        if hits[i] >= learn_frames and d == d:
            offset = d - background[i]
            margin = _margin(k, base, quadratic, background[i])
            judged += 1
            if offset < -margin:
                verdict[i] = 2
            else:
                verdict[i] = 1
                if offset > margin:
                    behind += 1
    return judged, behind


@njit(cache=True, nogil=True)
def learn(depth, background, hits, near, far, far_frames, k, base, quadratic, span,
          absorb_frames, learn_frames, reveal_frames):
    """Learn one depth image into the flat per-pixel state (see ``DepthBackground._learn``)."""
    one = np.float32(1.0)
    half = np.float32(0.5)
    for i in range(depth.size):
        d = depth[i]
        b = background[i]
        offset = d - b
        margin = _margin(k, base, quadratic, b)
        nearer = offset < -margin
        behind = offset > margin
        close = abs(offset) <= half * margin
        # At the scene's depth: a running mean over up to span readings.
        if close:
            count = min(hits[i] + one, span)
            background[i] = b + (d - b) / count
            hits[i] = count
        elif d == d and b != b:                     # never seen: the first reading
            background[i] = d
            hits[i] = one
        # In front: held out until absorb_frames readings.
        if nearer:
            near[i] += 1
        if close or behind:
            near[i] = 0
        if nearer and near[i] >= absorb_frames:
            background[i] = d
            hits[i] = np.float32(learn_frames)
            near[i] = 0
        # Behind, consistently: the scene uncovered.
        if behind:
            f = far[i]
            if abs(d - f) <= _margin(k, base, quadratic, f):
                far[i] = f + (d - f) / np.float32(far_frames[i] + 1)
                far_frames[i] += 1
            else:
                far[i] = d
                far_frames[i] = 1
        if close or nearer:
            far_frames[i] = 0
        if far_frames[i] >= reveal_frames:
            background[i] = far[i]
            hits[i] = np.float32(max(far_frames[i], learn_frames))
            near[i] = 0
            far_frames[i] = 0


def compile_kernel():
    """Compile (or load from the cache) both passes on a tiny image."""
    depth = np.ones(4, np.float32)
    state = [np.ones(4, np.float32), np.ones(4, np.float32), np.zeros(4, np.int32),
             np.ones(4, np.float32), np.zeros(4, np.int32)]
    scalars = (np.float32(4.0), np.float32(0.002), np.float32(0.005))
    judge(depth, state[0], state[1], *scalars, np.float32(1.0), np.zeros(4, np.uint8))
    learn(depth, *state, *scalars, np.float32(300.0), 300, 10, 5)
