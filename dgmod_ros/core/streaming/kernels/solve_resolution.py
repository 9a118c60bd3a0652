# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled pass of the background refit: each pixel's weighted normal equations.

:func:`~dgmod_ros.core.streaming.solve_resolution.carry_backgrounds` fits
every full-size pixel's time series on the solve's ``r`` temporal factors
``V`` (m x r) with the entries the solve called foreground weighted out.
Its sums ``G_i = sum_j w_ij v_j v_j^T`` and ``b_i = sum_j w_ij d_ij v_j``
of every channel are one pass over the window here, frame by frame along its
contiguous rows, threaded over blocks of pixels; as BLAS products the same
sums read the window and the weights several times and cost about three
times as much. The frames are read where they are, a snapshot's buffered
columns included (:meth:`~dgmod_ros.core.streaming.results.WindowSnapshot.frames`),
instead of a 640 x 480 window stacked only for this pass.
numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import numpy as np

from ...numba_setup import BLOCK_PIXELS, FAST_MATH, njit, prange, register_pass, typed_frames


@njit(parallel=True, cache=True, nogil=True, fastmath=FAST_MATH)
def _normal_equations(frames, held_out, temporal, ranks, gram, rhs):
    m, (channels, n) = len(frames), frames[0].shape
    block = BLOCK_PIXELS
    for b in prange((n + block - 1) // block):
        lo = b * block
        hi = min(n, lo + block)
        w = np.empty(hi - lo, dtype=np.float32)
        weighted = np.empty(hi - lo, dtype=np.float32)
        for j in range(m):
            held = held_out[j, lo:hi]
            for i in range(hi - lo):
                w[i] = np.float32(held[i] == 0)
            frame = frames[j]
            for channel in range(channels):
                d = frame[channel, lo:hi]
                for i in range(hi - lo):
                    weighted[i] = w[i] * d[i]
                r = ranks[channel]
                for a in range(r):
                    va = temporal[channel, j, a]
                    row = rhs[channel, a, lo:hi]
                    for i in range(hi - lo):
                        row[i] += va * weighted[i]
                    for c in range(a, r):
                        vac = va * temporal[channel, j, c]
                        row = gram[channel, a, c, lo:hi]
                        for i in range(hi - lo):
                            row[i] += vac * w[i]


def normal_equations(frames, held_out, temporals):
    """
    Return each channel's ``G`` (r, r, n) and ``b`` (r, n) of the weighted fit, as a list.

    One pass over the window for all channels: each entry's weight (1
    observed, 0 held out) is read once for every channel.

    Parameters
    ----------
    frames : sequence of m ndarrays (C, n) float32, or ndarray (m, C, n)
        The window frame by frame: a snapshot's buffered columns as they
        are (no window is stacked for the fit), or a window's frames (each
        one copied only where it is not C-ordered).
    held_out : ndarray (m, n) float32
        Non-zero where an entry is held out of the fit.
    temporals : sequence of C ndarrays (m, r_c) float32
        Each channel's temporal factors ``V``.

    """
    frames = typed_frames(frames)
    held_out = np.ascontiguousarray(held_out, dtype=np.float32)
    channels, n = frames[0].shape
    ranks = np.array([t.shape[1] for t in temporals], dtype=np.int64)
    r = int(ranks.max())
    temporal = np.zeros((channels, len(frames), r), dtype=np.float32)
    for channel, factors in enumerate(temporals):
        temporal[channel, :, :factors.shape[1]] = factors
    gram = np.zeros((channels, r, r, n), dtype=np.float32)
    rhs = np.zeros((channels, r, n), dtype=np.float32)
    _normal_equations(frames, held_out, temporal, ranks, gram, rhs)
    systems = []
    for channel, rank in enumerate(ranks):
        channel_gram = gram[channel, :rank, :rank]
        for a in range(rank):               # the pass fills the upper triangle
            channel_gram[a + 1:, a] = channel_gram[a, a + 1:]
        systems.append((channel_gram, rhs[channel, :rank]))
    return systems


def normal_equations_reference(frames, held_out, temporals):
    """Return :func:`normal_equations` computed in numpy (float32 sums in another order)."""
    data = np.stack([np.asarray(frame, dtype=np.float32) for frame in frames])    # (m, C, n)
    weight = (np.asarray(held_out) == 0).astype(np.float32)                       # (m, n)
    return [(np.einsum('ja,jb,jn->abn', temporal, temporal, weight),
             np.einsum('ja,jn->an', temporal, weight * data[:, channel]))
            for channel, temporal in enumerate(temporals)]


def _examples():
    """Return windows of a few frames, channels of ranks 2, 1 and 3, some entries held out."""
    rng = np.random.default_rng(0)
    m, n = 6, 2500
    frames = rng.uniform(0, 1, (m, 3, n)).astype(np.float32)
    held_out = (rng.uniform(0, 1, (m, n)) < 0.2).astype(np.float32)
    temporals = [rng.normal(0, 1, (m, rank)).astype(np.float32) for rank in (2, 1, 3)]
    return [(frames, held_out, temporals), (list(frames), held_out, temporals[:1] * 3)]


# Float32 sums reassociated (fastmath): equal to rounding, at most a few
# units in the last place of sums of six terms of order one.
register_pass(normal_equations, _examples, normal_equations_reference, atol=1e-5, rtol=1e-5)
