# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The lighting test in one compiled pass over the candidate pixels (same answers as numpy).

:func:`explained_pixels_reference`
gathers the candidates' colours, forms the brightness ratio and the
chromaticity distortion in a dozen numpy passes and describes every
candidate's texture. :func:`explained_pixels` visits each candidate once:
brightness, chromaticity, then the LBSP distance only for a candidate the
first cues still call light (the reference ANDs the cues, so the others'
distance cannot change the answer). The arithmetic is the reference's in
float32, operation for operation (``einsum``'s sums of products add the
channels in order, with no fused multiply-add; Python scalars enter numpy's
arithmetic as float32), so the answers are the same bit for bit; inputs of
another type go to the reference. :func:`window_chroma` is the same
chromaticity arithmetic over a whole window (the solve's chromaticity levels).

numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import math

import numpy as np

from .texture import channel_bits, descriptor_distance, OFFSETS, RELATIVE_THRESHOLD, window_offsets
from ...numba_setup import njit, register_pass

# Smallest squared background norm: a black pixel has no chromaticity.
_DARK = np.float32(1e-6)


def distortion(frame, background):
    """
    Return the brightness ratio ``alpha`` and chromaticity distortion ``c`` of a frame.

    Parameters
    ----------
    frame, background : ndarray (C, ...)
        Colour channels first, any trailing shape.

    Returns
    -------
    alpha, chroma : ndarray (...) float32

    """
    frame = np.asarray(frame, dtype=np.float32)
    background = np.asarray(background, dtype=np.float32)
    energy = np.maximum(np.einsum('c...,c...->...', background, background), _DARK)
    alpha = np.einsum('c...,c...->...', frame, background) / energy
    across = frame - alpha[None] * background
    return alpha, np.sqrt(np.einsum('c...,c...->...', across, across))


@njit(cache=True, nogil=True, inline='always')
def _nan_maximum(a, b):
    """Return ``np.maximum(a, b)``: NaN if either is NaN."""
    if a != a or b != b:
        return a + b
    return a if a >= b else b


@njit(cache=True, nogil=True)
def _explain(frame, background, rows, cols, noise, chroma_level, candidates, k, relative,
             use_chroma, use_texture, texture_bits, offsets, window, explained):
    channels = frame.shape[0]
    one = np.float32(1.0)
    for i in range(candidates.shape[0]):
        if not candidates[i]:
            explained[i] = False
            continue
        row, col = i // cols, i % cols
        energy = np.float32(0.0)
        dot = np.float32(0.0)
        for c in range(channels):
            energy += background[c, i] * background[c, i]
            dot += frame[c, i] * background[c, i]
        energy = _nan_maximum(energy, _DARK)
        alpha = dot / energy
        light = abs(alpha - one) <= relative
        if light and use_chroma:
            across = np.float32(0.0)
            for c in range(channels):
                difference = frame[c, i] - alpha * background[c, i]
                across += difference * difference
            light = math.sqrt(across) <= k * chroma_level[i]
        if light and use_texture:
            level = k * noise[i]
            bits = 0
            for c in range(channels):
                limit = _nan_maximum(relative * background[c, i], level)
                bits += channel_bits(frame, background, c, row, col, rows, cols, limit,
                                     offsets, window)
            light = bits <= texture_bits
        explained[i] = light


def explained_pixels(columns, background, noise, k, shape, candidates, chroma_level, use_chroma,
                     use_texture, texture_bits):
    """
    Return :meth:`LightingTest.explains`'s answer (n,) bool, or None for the reference's inputs.

    ``use_chroma``, ``use_texture`` and ``texture_bits`` are the test's parameters
    (:class:`~dgmod_ros.core.streaming.photometric.LightingTest`), the
    others :meth:`LightingTest.explains`'s.

    None unless the data are float32, ``k`` is a Python number and the
    chromaticity levels (if given) are float32: numpy computes in float64 otherwise.
    """
    if (columns.dtype != np.float32 or background.dtype != np.float32
            or type(k) not in (float, int)
            or (chroma_level is not None and np.asarray(chroma_level).dtype != np.float32)):
        return None
    rows, cols, channels = shape
    count = rows * cols
    level = np.asarray(noise, dtype=np.float32)
    if level.shape != (count,):
        level = np.full(count, level, dtype=np.float32)
    level = np.ascontiguousarray(level)
    chroma = level if chroma_level is None else np.ascontiguousarray(chroma_level.reshape(-1))
    explained = np.empty(count, dtype=bool)
    _explain(np.ascontiguousarray(columns), np.ascontiguousarray(background), rows, cols,
             level, chroma, np.ascontiguousarray(candidates.reshape(-1)), np.float32(k),
             np.float32(RELATIVE_THRESHOLD), bool(use_chroma), bool(use_texture),
             int(texture_bits), OFFSETS, window_offsets(cols), explained)
    return explained


# Entries per block of the window's chromaticity pass: its per-entry sums
# stay in the first-level cache while the channels are added one by one.
_CHROMA_BLOCK = 512


@njit(cache=True, nogil=True)
def _window_chroma(data, residual, chroma):
    # data, residual (C, N); chroma (N,). Channel by channel over a block of
    # entries, each step a unit-stride loop that the compiler vectorises; the
    # same operations per entry, in the same order, as one entry at a time.
    channels, count = data.shape
    energy = np.empty(_CHROMA_BLOCK, dtype=np.float32)
    dot = np.empty(_CHROMA_BLOCK, dtype=np.float32)
    across = np.empty(_CHROMA_BLOCK, dtype=np.float32)
    for lo in range(0, count, _CHROMA_BLOCK):
        size = min(_CHROMA_BLOCK, count - lo)
        energy[:size] = 0.0
        dot[:size] = 0.0
        across[:size] = 0.0
        for c in range(channels):
            d = data[c, lo:lo + size]
            e = residual[c, lo:lo + size]
            for i in range(size):
                background = d[i] - e[i]
                energy[i] += background * background
                dot[i] += d[i] * background
        for i in range(size):
            energy[i] = dot[i] / _nan_maximum(energy[i], _DARK)            # alpha
        for c in range(channels):
            d = data[c, lo:lo + size]
            e = residual[c, lo:lo + size]
            for i in range(size):
                difference = d[i] - energy[i] * (d[i] - e[i])
                across[i] += difference * difference
        out = chroma[lo:lo + size]
        for i in range(size):
            out[i] = math.sqrt(across[i])


def explained_pixels_reference(columns, background, noise, k, shape, candidates, chroma_level,
                               use_chroma, use_texture, texture_bits):
    """
    Return :func:`explained_pixels`'s answer computed in numpy, for any inputs.

    The texture cue's LBSP distance is the compiled
    :func:`~dgmod_ros.core.streaming.kernels.texture.descriptor_distance`
    (checked against its own reference): what this reference states is how
    the cues combine.
    """
    pixels = np.flatnonzero(candidates)
    explained = np.zeros(candidates.shape, dtype=bool)
    if pixels.size == 0:
        return explained
    level = np.broadcast_to(np.asarray(noise, dtype=np.float32), candidates.shape)[pixels]
    frame, reference = columns[:, pixels], background[:, pixels]
    alpha, chroma = distortion(frame, reference)
    light = np.abs(alpha - 1.0) <= RELATIVE_THRESHOLD
    if use_chroma:
        chroma_level = level if chroma_level is None else chroma_level[pixels]
        light &= chroma <= k * chroma_level
    if use_texture:
        rows, cols, channels = shape
        threshold = np.maximum(RELATIVE_THRESHOLD * reference, k * level)
        bits = descriptor_distance(columns.reshape(channels, rows, cols),
                                   background.reshape(channels, rows, cols), threshold, pixels)
        light &= bits <= texture_bits
    explained[pixels] = light
    return explained


def window_chroma(data, residual):
    """
    Return the chromaticity distortion (n, m) float32 of a window against ``D - residual``.

    :func:`distortion`'s second output
    for ``(data, data - residual)`` in one pass, without its (C, n, m)
    temporaries; None for inputs that are not float32 (the caller runs numpy).
    """
    if data.dtype != np.float32 or residual.dtype != np.float32:
        return None
    chroma = np.empty(data.shape[1:], dtype=np.float32)
    channels = data.shape[0]
    _window_chroma(np.ascontiguousarray(data).reshape(channels, -1),
                   np.ascontiguousarray(residual).reshape(channels, -1), chroma.reshape(-1))
    return chroma


def window_chroma_reference(data, residual):
    """Return :func:`window_chroma` computed in numpy, for any inputs."""
    return distortion(data, data - residual)[1]


def _explain_examples():
    """Return a frame with shadows, reflections and a body; each cue on and off."""
    rng = np.random.default_rng(0)
    rows, cols = 20, 30
    background = rng.uniform(0.05, 0.95, (3, rows * cols)).astype(np.float32)
    light = rng.choice([0.7, 1.0, 1.2], rows * cols).astype(np.float32)
    frame = background * light
    frame[:, 100:160] = rng.uniform(0, 1, (3, 60))                 # a body
    noise = rng.uniform(0.005, 0.03, rows * cols).astype(np.float32)
    candidates = rng.uniform(0, 1, rows * cols) < 0.6
    chroma_level = rng.uniform(0.005, 0.05, rows * cols).astype(np.float32)
    return [(frame, background, level, 6.0, (rows, cols, 3), candidates, chroma, *cues, 8)
            for level, chroma in ((noise, chroma_level), (0.01, None))
            for cues in ((True, True), (True, False), (False, True))]


def _chroma_examples():
    rng = np.random.default_rng(1)
    data = rng.uniform(0, 1, (3, 700, 6)).astype(np.float32)
    return [(data, rng.normal(0, 0.05, data.shape).astype(np.float32))]


register_pass(explained_pixels, _explain_examples, explained_pixels_reference)
register_pass(window_chroma, _chroma_examples, window_chroma_reference)
