# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The depth background's per-frame update in two compiled passes over the pixels.

:class:`~dgmod_ros.core.depth_background.DepthBackground` judges a depth
image against its model and then learns from it. In numpy that is about
thirty passes over (h, w) arrays with their temporaries (9 ms at 640 x 480
here); :func:`judge` and :func:`learn` read each pixel's state once and do
the same float32 arithmetic in the same order: the same model and verdicts,
bit for bit, as their numpy references :func:`judge_reference` and
:func:`learn_reference` (``test/test_compiled_passes.py``,
``test/test_depth_background.py``). Serial and ``nogil``: the
depth callback runs beside the solve thread, whose kernels own the threads.
numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ..numba_setup import njit, register_pass


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


# The numpy references of the two passes: the same arguments, the same
# results, written into the same arrays (DepthBackground(compiled=False)).
def _relations(depth, background, k, base, quadratic):
    """Return where ``depth`` is nearer, behind, within half the band of ``background``."""
    with np.errstate(invalid='ignore'):
        # NaN (no reading, or a pixel never seen) compares False everywhere.
        offset = depth - background
        margin = k * (base + quadratic * background * background)
        # Learnt from the readings within half the band only: a person just
        # in front of the wall, whose noise reaches into the band now and
        # then, would otherwise pull the mean, and the band, towards them.
        return (offset < -margin, offset > margin,
                np.abs(offset) <= np.float32(0.5) * margin)


def judge_reference(depth, background, hits, k, base, quadratic, learn_frames, verdict):
    """Write :func:`judge`'s verdicts into ``verdict``; return its counts, in numpy."""
    nearer, behind, _ = _relations(depth, background, k, base, quadratic)
    # A trusted pixel with a reading is judged: in front, else at or behind.
    judged = (hits >= learn_frames) & ~np.isnan(depth)
    verdict[:] = 0
    verdict[judged] = 1
    verdict[judged & nearer] = 2
    return np.count_nonzero(judged), np.count_nonzero(judged & behind)


def learn_reference(depth, background, hits, near, far, far_frames, k, base, quadratic, span,
                    absorb_frames, learn_frames, reveal_frames):
    """Learn one depth image into the flat per-pixel state as :func:`learn` does, in numpy."""
    nearer, behind, close = _relations(depth, background, k, base, quadratic)
    first = ~np.isnan(depth) & np.isnan(background)
    # At the scene's depth: a running mean over up to span readings.
    count = np.minimum(hits + np.float32(1), span)
    with np.errstate(invalid='ignore'):
        step = np.where(close, (depth - background) / count, np.float32(0))
    np.add(background, step, out=background, where=close)
    np.copyto(hits, count, where=close)
    # Never seen before: the first reading starts the pixel.
    np.copyto(background, depth, where=first)
    np.copyto(hits, np.float32(1), where=first)
    # In front: held out until absorb_frames readings (a parked object).
    near += nearer
    near[close | behind] = 0
    absorbed = nearer & (near >= absorb_frames)
    np.copyto(background, depth, where=absorbed)
    np.copyto(hits, np.float32(learn_frames), where=absorbed)
    near[absorbed] = 0
    # Behind, consistently: the scene uncovered.
    with np.errstate(invalid='ignore'):
        agrees = behind & (np.abs(depth - far) <= k * (base + quadratic * far * far))
    restart = behind & ~agrees
    np.copyto(far, depth, where=restart)
    far_frames[restart] = 1
    with np.errstate(invalid='ignore'):
        step = (depth - far) / (far_frames + 1).astype(np.float32)
    np.add(far, step, out=far, where=agrees)
    far_frames += agrees
    far_frames[close | nearer] = 0
    revealed = far_frames >= reveal_frames
    np.copyto(background, far, where=revealed)
    # Trusted at once: the scene's far side, seen reveal_frames times.
    np.copyto(hits, np.maximum(far_frames, learn_frames).astype(np.float32), where=revealed)
    near[revealed] = 0
    far_frames[revealed] = 0


_NOISE = (np.float32(4.0), np.float32(0.002), np.float32(0.005))    # k, base, quadratic


def _state(rng, pixels):
    """Return a random flat per-pixel state: background, hits, near, far, far_frames."""
    background = rng.uniform(0.5, 4.0, pixels).astype(np.float32)
    background[::7] = np.nan                                    # never seen
    return [background, rng.integers(0, 12, pixels).astype(np.float32),
            rng.integers(0, 6, pixels).astype(np.int32),
            rng.uniform(0.5, 4.0, pixels).astype(np.float32),
            rng.integers(0, 6, pixels).astype(np.int32)]


def _depth(rng, background):
    """Return readings near, at and behind ``background``, some missing."""
    depth = background + rng.choice([-0.5, 0.0, 0.001, 0.5], background.size).astype(np.float32)
    depth[::5] = np.nan
    depth[::11] = rng.uniform(0.5, 4.0, depth[::11].size)
    return depth.astype(np.float32)


def _judge_examples():
    rng = np.random.default_rng(0)
    background, hits = _state(rng, 600)[:2]
    return [(_depth(rng, background), background, hits, *_NOISE, np.float32(learn_frames),
             np.zeros(600, np.uint8)) for learn_frames in (1.0, 10.0)]


def _learn_examples():
    rng = np.random.default_rng(1)
    state = _state(rng, 600)
    return [(_depth(rng, state[0]), *state, *_NOISE, np.float32(30.0), 3, 10, 5)]


_PASSES = (register_pass(judge, _judge_examples, reference=judge_reference),
           register_pass(learn, _learn_examples, reference=learn_reference))


def compile_kernel():
    """Compile (or load from the cache) both passes (the depth outputs' configure step)."""
    for compiled_pass in _PASSES:
        compiled_pass.warm_up()
