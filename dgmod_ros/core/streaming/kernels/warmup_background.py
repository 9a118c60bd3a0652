# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The warm-up's background and noise level in one compiled pass each (numpy's values, bit for bit).

Before the first window solve (the first frames, and again after every
scene-change restart) a frame's background is each entry's median over the
buffered frames, and the noise level is read from the magnitudes of the
differences of consecutive frames
(:func:`~dgmod_ros.core.streaming.noise_levels.warmup_noise`). In numpy those
stack the buffered frames, take ``np.median`` along the short frame axis
(a partition per entry) and ``np.diff`` of the stack with the frame: at
640 x 480 x 3 that was 150-180 ms a frame, in the image callback, which lost
the frames that came meanwhile. Here the frames are read where they are (a
typed list), each entry's few values are sorted by a network of
compare-exchanges over whole rows of a block (up to :data:`NETWORK_FRAMES`
frames; numpy beyond, where the network's square growth costs more than the
partitions), and the difference magnitudes are written without temporaries.
Serial and ``nogil``: they run in the image callback beside the solve
thread's kernels.

numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ...numba_setup import BLOCK_PIXELS, njit, register_pass, typed_frames


#: Most frames whose per-entry median the compiled network takes (the
#: default warm-up has at most 5; ``min_frames`` may ask for up to 300).
NETWORK_FRAMES = 16


@njit(cache=True, nogil=True, inline='always')
def _order(low, high):
    """Put the smaller of two equally long rows' entries in ``low``, the larger in ``high``."""
    for i in range(low.size):
        a, b = low[i], high[i]
        low[i] = a if a <= b else b
        high[i] = b if a <= b else a


@njit(cache=True, nogil=True)
def _entry_medians(frames, out):
    count = len(frames)
    half = count // 2
    two = np.float32(2.0)
    nan = np.float32(np.nan)
    # A block of entries per frame: one row of scratch each, in cache.
    values = np.empty((count, BLOCK_PIXELS), dtype=np.float32)
    for channel in range(out.shape[0]):
        for lo in range(0, out.shape[1], BLOCK_PIXELS):
            hi = min(out.shape[1], lo + BLOCK_PIXELS)
            rows = values[:, :hi - lo]
            for j in range(count):
                rows[j] = frames[j][channel, lo:hi]
            # An insertion network on whole rows: after it, row j holds each
            # entry's j-th smallest value (the loops vectorise, a per-entry
            # sort does not).
            for a in range(1, count):
                for b in range(a, 0, -1):
                    _order(rows[b - 1], rows[b])
            target = out[channel, lo:hi]
            if count % 2:
                target[:] = rows[half]
            else:                           # np.median: the mean of the middle two
                for i in range(hi - lo):
                    target[i] = (rows[half - 1, i] + rows[half, i]) / two
            for j in range(count):          # numpy's median of an entry with a NaN
                row = frames[j][channel, lo:hi]
                for i in range(hi - lo):
                    if row[i] != row[i]:
                        target[i] = nan


@njit(cache=True, nogil=True)
def _difference_magnitudes(frames, out):
    channels = frames[0].shape[0]
    for j in range(len(frames) - 1):
        older, newer = frames[j], frames[j + 1]
        row = out[j]
        for i in range(row.size):
            row[i] = abs(newer[0, i] - older[0, i])
        for channel in range(1, channels):
            a, b = older[channel], newer[channel]
            for i in range(row.size):
                value = abs(b[i] - a[i])
                largest = row[i]
                # np.max over the channels: a NaN, once there, stays.
                row[i] = value if largest == largest and not value <= largest else largest


def entry_medians(frames):
    """
    Return each entry's median over ``frames`` (C, n), as ``np.median`` of their stack.

    ``frames`` is a non-empty sequence of (C, n) float32 arrays; an even
    count gives the mean of the middle two in float32, and an entry with a
    NaN in any frame gives NaN, as numpy does.
    """
    if len(frames) > NETWORK_FRAMES:
        return entry_medians_reference(frames)
    frames = typed_frames(frames)
    out = np.empty(frames[0].shape, dtype=np.float32)
    _entry_medians(frames, out)
    return out


def difference_magnitudes(frames):
    """
    Return ``np.abs(np.diff(stack, axis=-1)).max(axis=0).T`` of the frames' stack, (k - 1, n).

    Row ``j`` holds, at every pixel, the largest absolute difference over the
    channels between frames ``j + 1`` and ``j`` (NaN where a channel's is).
    """
    frames = typed_frames(frames)
    out = np.empty((len(frames) - 1, frames[0].shape[1]), dtype=np.float32)
    if len(frames) > 1:
        _difference_magnitudes(frames, out)
    return out


def entry_medians_reference(frames):
    """Return :func:`entry_medians` computed in numpy."""
    return np.median(np.stack(frames, axis=2), axis=2)


def difference_magnitudes_reference(frames):
    """Return :func:`difference_magnitudes` computed in numpy."""
    return np.abs(np.diff(np.stack(frames, axis=-1), axis=-1)).max(axis=0).T


def _examples():
    """Return one to six frames of three channels over more than a block, some NaN entries."""
    rng = np.random.default_rng(0)
    examples = []
    for count in range(1, 7):
        frames = [rng.uniform(0, 1, (3, 2500)).astype(np.float32) for _ in range(count)]
        frames[-1][:, ::97] = np.nan
        examples.append((frames,))
    return examples


register_pass(entry_medians, _examples, entry_medians_reference)
register_pass(difference_magnitudes, _examples, difference_magnitudes_reference)
