# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
How much of each foreground blob moved, in one compiled pass over the labelled pixels.

:class:`~dgmod_ros.core.streaming.blobs.BlobMotion` asks of every blob which
share of its pixels changed by more than ``k`` noise levels against an
earlier frame. :func:`moving_share` counts them in one serial ``nogil`` pass
over the labelled pixels only (the background's label 0, most of a frame,
is skipped); the shares are those of :func:`moving_share_reference`, the
numpy formulation, bit for bit (the background's label 0 aside, which no
test reads): the same float32 comparisons, integer counts, the same float64
division. numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ...numba_setup import njit, register_pass


@njit(cache=True, nogil=True)
def _moving_counts(labels, frame, earlier, noise, k, pixels, moved):
    """
    Count each label's pixels and those whose change exceeds ``k`` noise levels.

    A change is the largest absolute difference over the channels (NaN in
    any channel: no change, as numpy's ``max`` then ``>``).
    """
    channels = frame.shape[0]
    for i in range(labels.shape[0]):
        label = labels[i]
        if label == 0:
            continue
        pixels[label] += 1
        change = np.float32(0.0)
        finite = True
        for c in range(channels):
            value = abs(frame[c, i] - earlier[c, i])
            if value != value:
                finite = False
            elif value > change:
                change = value
        if finite and change > k * noise[i]:
            moved[label] += 1


def moving_share(labels, count, frame, earlier, noise, k):
    """
    Return per label (count,) float64 the share of pixels changed by over ``k`` levels, or None.

    ``labels`` (rows, cols) int32 are the blobs of ``count`` labels;
    ``frame``, ``earlier`` (C, n) and ``noise`` (n,) or a float. None unless
    the pass reproduces numpy's float32 arithmetic: float32 data, a float32
    level per pixel and a Python ``k`` (numpy takes it as float32).
    """
    if not (type(k) in (float, int) and isinstance(noise, np.ndarray)
            and noise.dtype == np.float32 and noise.size == labels.size
            and frame.dtype == np.float32 and earlier.dtype == np.float32):
        return None
    pixels = np.zeros(count, dtype=np.int64)
    moved = np.zeros(count, dtype=np.int64)
    _moving_counts(labels.reshape(-1), np.ascontiguousarray(frame),
                   np.ascontiguousarray(earlier), np.ascontiguousarray(noise.ravel()),
                   np.float32(k), pixels, moved)
    return moved / np.maximum(pixels, 1)


def moving_share_reference(labels, count, frame, earlier, noise, k):
    """Return :func:`moving_share` computed in numpy, for any inputs (label 0: background, 0)."""
    flat = labels.ravel()
    moved = np.abs(frame - earlier).max(axis=0) > k * noise
    share = (np.bincount(flat, moved, minlength=count)
             / np.maximum(np.bincount(flat, minlength=count), 1))
    share[0] = 0.0
    return share


def _examples():
    """Return three blobs of a frame against an earlier one, NaN entries among them."""
    rng = np.random.default_rng(0)
    labels = np.zeros((20, 30), dtype=np.int32)
    labels[2:8, 3:12], labels[10:18, 5:9], labels[12:19, 20:29] = 1, 2, 3
    frame = rng.uniform(0, 1, (3, 600)).astype(np.float32)
    earlier = frame + rng.normal(0, 0.05, frame.shape).astype(np.float32)
    earlier[1, ::37] = np.nan
    noise = rng.uniform(0.01, 0.03, 600).astype(np.float32)
    return [(labels, 4, frame, earlier, noise, k) for k in (1.0, 3.0)]


register_pass(moving_share, _examples, moving_share_reference)
