# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled sweeps of the Potts field's mean-field decision (same masks as numpy, bit for bit).

:func:`mean_field_spins_reference` spends
a sweep in nine numpy passes over the frame (box filter, subtraction, scaling,
addition, clip, halving, tanh and their temporaries). Here a sweep is one
serial ``nogil`` pass (:func:`_sweep`) plus numpy's ``tanh`` on the few
pixels whose log-odds are undecided, and the arithmetic is the reference's,
operation for operation, in float32:

- the 5 x 5 box sum of the spins is taken in float64, as OpenCV's
  ``boxFilter`` takes it for float32 input. A spin is +-1 or ``tanh`` of a
  float32; while every nonzero spin is at least ``2**-25`` in magnitude,
  every partial sum of at most 25 of them is exact in float64, so any order
  of summation gives OpenCV's sum. A smaller spin (log-odds within
  ``1e-7`` of 0 for a pixel whose unary term is exactly 0) or a NaN spin
  (a non-finite frame: OpenCV's running sums carry it along the row) makes
  :func:`mean_field_spins` return None and the caller runs the reference;
- ``tanh`` is numpy's own (its float32 SIMD routine, not the C library's),
  applied only where the halved log-odds are below :data:`SATURATED` in
  magnitude: beyond, numpy's float32 ``tanh`` is exactly +-1 (checked by
  ``test/test_decision.py`` over the whole range), and a frame's pixels are
  mostly far from their threshold;
- a row whose pixels would all get spin -1 from a neighbourhood of -1 spins
  is not computed while the rows of its neighbourhood hold only -1 spins:
  the arithmetic would give exactly -1 there (the box sum is then exactly
  ``-(2 r + 1)**2``), and most of a frame is such rows.

numba's process-wide settings come with ``njit`` from
:mod:`~dgmod_ros.core.numba_setup`.
"""

import cv2
import numpy as np

from ...numba_setup import njit, register_pass

#: Halved log-odds from which numpy's float32 tanh is exactly +-1 (it is from 10.00003).
SATURATED = np.float32(10.5)
# Smallest nonzero spin magnitude for which the float64 box sums are exact.
_EXACT_SPIN = np.float32(2.0 ** -25)


@njit(cache=True, nogil=True, inline='always')
def _half_logit(unary, neighbours, beta, logit_cap):
    """Return half the clipped log-odds, as the reference's float32 operations."""
    logit = unary + beta * neighbours
    if logit > logit_cap:                   # np.clip: NaN stays NaN
        logit = logit_cap
    elif logit < -logit_cap:
        logit = -logit_cap
    return logit / np.float32(2.0)


@njit(cache=True, nogil=True)
def _unary(distance, noise, z_cap, k_squared, beta, logit_cap, quiet_neighbours, unary, spin,
           unary_quiet, spin_quiet):
    """
    Write the unary log-odds, the plain rule's spins (the field's start) and the quiet rows.

    ``z_cap`` and ``k_squared`` are each pixel's own (rows, cols): the
    moving-texture rule gives pixels their own ``k``.

    ``unary_quiet[r]``: every pixel of row ``r`` gets spin -1 when its
    neighbours sum to ``quiet_neighbours`` (all -1); ``spin_quiet[r]``: every
    spin of row ``r`` is -1.
    """
    rows, cols = distance.shape
    two = np.float32(2.0)
    one = np.float32(1.0)
    for r in range(rows):
        row_distance = distance[r]
        row_noise = noise[r]
        row_cap = z_cap[r]
        row_k_squared = k_squared[r]
        row_unary = unary[r]
        row_spin = spin[r]
        positive = 0
        loud = 0
        for c in range(cols):
            z = row_distance[c] / row_noise[c]
            if z > row_cap[c]:              # np.minimum: NaN stays NaN
                z = row_cap[c]
            u = (z * z - row_k_squared[c]) / two
            row_unary[c] = u
            row_spin[c] = one if u > 0 else -one
            positive += u > 0
            loud += not (_half_logit(u, quiet_neighbours, beta, logit_cap) <= -SATURATED)
        unary_quiet[r] = loud == 0
        spin_quiet[r] = positive == 0


@njit(cache=True, nogil=True)
def _clamped_sum(row, c, radius):
    total = 0.0
    for d in range(-radius, radius + 1):
        total += row[min(max(c + d, 0), row.shape[0] - 1)]
    return total


@njit(cache=True, nogil=True)
def _sweep(spin, unary, radius, beta, logit_cap, unary_quiet, spin_quiet, new_spin, new_quiet,
           pending_index, pending_value, row_sums, column_sum, row_half):
    """
    One mean-field sweep from ``spin`` into ``new_spin``; return the undecided pixels' count.

    A pixel whose halved log-odds are saturated gets its spin +-1 here; the
    others' halved log-odds go to ``pending_value`` (flat index in
    ``pending_index``) for numpy's tanh. The loops run along rows over views
    indexed from 0, so that the compiler vectorises them (no negative-index
    checks); each sum still adds in a fixed order.
    """
    rows, cols = spin.shape
    one = np.float32(1.0)
    inner = max(cols - 2 * radius, 0)
    for r in range(rows):               # horizontal sums of 2 r + 1 spins, float64
        row = spin[r]
        sums = row_sums[r]
        if spin_quiet[r]:
            sums[:] = -(2.0 * radius + 1.0)
            continue
        middle = sums[radius:radius + inner]
        for j in range(inner):
            middle[j] = 0.0
        for d in range(-radius, radius + 1):
            shifted = row[radius + d:radius + d + inner]
            for j in range(inner):
                middle[j] += shifted[j]
        for c in range(min(radius, cols)):              # the replicated borders
            sums[c] = _clamped_sum(row, c, radius)
        for c in range(max(cols - radius, min(radius, cols)), cols):
            sums[c] = _clamped_sum(row, c, radius)
    count = 0
    for r in range(rows):
        first, last = max(r - radius, 0), min(r + radius, rows - 1)
        if unary_quiet[r] and spin_quiet[first:last + 1].all():
            new_spin[r, :] = -one
            new_quiet[r] = True
            continue
        for c in range(cols):
            column_sum[c] = 0.0
        for d in range(-radius, radius + 1):
            above = row_sums[min(max(r + d, 0), rows - 1)]
            for c in range(cols):
                column_sum[c] += above[c]
        row = spin[r]
        row_unary = unary[r]
        row_spin = new_spin[r]
        undecided = 0
        positive = 0
        for c in range(cols):
            half = _half_logit(row_unary[c], np.float32(column_sum[c]) - row[c], beta,
                               logit_cap)
            row_half[c] = half
            up = half >= SATURATED
            down = half <= -SATURATED
            row_spin[c] = one if up else -one
            undecided += not (up or down)       # NaN too: numpy's tanh decides
            positive += not down
        new_quiet[r] = positive == 0
        if undecided:
            for c in range(cols):
                half = row_half[c]
                if not (half >= SATURATED or half <= -SATURATED):
                    pending_index[count] = r * cols + c
                    pending_value[count] = half
                    count += 1
    return count


@njit(cache=True, nogil=True)
def _scatter(pending_index, pending_value, count, spin):
    """
    Write the tanh values into the spins; return False where the reference's sums may differ.

    That is a nonzero spin too small for exact float64 box sums, or a NaN
    spin (a non-finite frame): OpenCV's running sums carry a NaN along the
    rest of its row and column, the kernel's direct sums do not.
    """
    reproducible = True
    flat = spin.reshape(-1)
    for p in range(count):
        value = pending_value[p]
        flat[pending_index[p]] = value
        if value != value or (value != 0 and abs(value) < _EXACT_SPIN):
            reproducible = False
    return reproducible


def mean_field_spins(distance, noise, k, beta, rows, cols, sweeps, radius, z_cap, logit_cap):
    """
    Return the field's spins (rows, cols) float32 after ``sweeps`` sweeps, or None.

    None when the float64 box sums could be inexact (see the module
    docstring) or the inputs are not those the kernel reproduces (float32
    distances; float32 noise levels or a Python float; ``k`` one for all
    pixels or each pixel's own; a Python ``beta``): the caller then runs the
    numpy reference. Arguments as
    :func:`~dgmod_ros.core.streaming.coherence.mean_field_mask_reference`,
    with its constants ``z_cap`` (times ``k``) and ``logit_cap``.
    """
    distance = np.reshape(distance, -1)
    # numpy computes in float32 with a Python scalar beta only (a numpy float64 promotes).
    if distance.dtype != np.float32 or type(beta) not in (float, int):
        return None
    # The reference's k: float32, one for all pixels or each pixel's own.
    k = np.reshape(np.asarray(k, dtype=np.float32), -1)
    if k.size not in (1, distance.size):
        return None
    if type(noise) in (float, int):         # numpy takes a Python scalar as float32
        noise = np.full(distance.size, np.float32(noise))
    elif not (isinstance(noise, np.ndarray) and noise.dtype == np.float32
              and noise.size == distance.size):
        return None
    shape = (int(rows), int(cols))
    side = 2 * int(radius) + 1
    beta32 = np.float32(beta)
    cap = np.float32(logit_cap)
    unary = np.empty(shape, dtype=np.float32)
    spin = np.empty(shape, dtype=np.float32)
    quiet = np.empty(shape[0], dtype=np.bool_)
    unary_quiet = np.empty(shape[0], dtype=np.bool_)
    # The neighbours of a spin -1 among -1 spins, as the reference's float32 subtraction.
    quiet_neighbours = np.float32(-side * side) - np.float32(-1.0)
    # Written into new arrays, not broadcast: a broadcast view is read-only,
    # and numba compiles a read-only argument apart, in the image callback.
    z_caps = np.empty(shape, dtype=np.float32)
    np.multiply(np.float32(z_cap), k, out=z_caps.reshape(-1))
    k_squared = np.empty(shape, dtype=np.float32)
    np.multiply(k, k, out=k_squared.reshape(-1))
    _unary(np.ascontiguousarray(distance).reshape(shape),
           np.ascontiguousarray(noise).reshape(shape), z_caps, k_squared, beta32, cap,
           quiet_neighbours, unary, spin, unary_quiet, quiet)
    new_spin = np.empty_like(spin)
    new_quiet = np.empty_like(quiet)
    row_sums = np.empty(shape, dtype=np.float64)
    column_sum = np.empty(shape[1], dtype=np.float64)
    row_half = np.empty(shape[1], dtype=np.float32)
    pending_index = np.empty(distance.size, dtype=np.int64)
    pending_value = np.empty(distance.size, dtype=np.float32)
    for _ in range(int(sweeps)):
        count = _sweep(spin, unary, int(radius), beta32, cap, unary_quiet, quiet, new_spin,
                       new_quiet, pending_index, pending_value, row_sums, column_sum, row_half)
        undecided = pending_value[:count]
        np.tanh(undecided, out=undecided)
        if not _scatter(pending_index, pending_value, count, new_spin):
            return None
        spin, new_spin = new_spin, spin
        quiet, new_quiet = new_quiet, quiet
    return spin


def mean_field_spins_reference(distance, noise, k, beta, rows, cols, sweeps, radius, z_cap,
                               logit_cap):
    """Return :func:`mean_field_spins` computed in numpy and OpenCV, for any inputs."""
    k = np.reshape(np.asarray(k, dtype=np.float32), -1)
    z = np.minimum(np.reshape(distance, -1) / noise, z_cap * k)
    unary = ((z * z - k * k) / 2).astype(np.float32).reshape(rows, cols)
    side = 2 * int(radius) + 1
    spin = np.where(unary > 0, np.float32(1), np.float32(-1))      # the plain rule
    for _ in range(int(sweeps)):
        # Sum of the neighbours' expected spins (the pixel itself excluded).
        neighbours = cv2.boxFilter(spin, -1, (side, side), normalize=False,
                                   borderType=cv2.BORDER_REPLICATE) - spin
        logit = np.clip(unary + beta * neighbours, -logit_cap, logit_cap)
        spin = np.tanh(logit / 2)                  # 2 q - 1 with q = sigmoid(logit)
    return spin


def _examples():
    """Return fields of a frame with blobs: one noise level and k for all, or each pixel's own."""
    rng = np.random.default_rng(0)
    rows, cols = 30, 40
    z = np.abs(rng.normal(0, 2.5, (rows, cols))).astype(np.float32)
    z[5:15, 8:20] += 8.0
    noise = rng.uniform(0.005, 0.05, rows * cols).astype(np.float32)
    distance = (z.ravel() * noise).astype(np.float32)
    k = np.where(rng.uniform(0, 1, rows * cols) < 0.2, 4.5, 6.0).astype(np.float32)
    return [(distance, 0.02, 6.0, 2.0, rows, cols, 5, 2, 3.0, 50.0),
            (distance, noise, k, 1.3, rows, cols, 5, 2, 3.0, 50.0)]


register_pass(mean_field_spins, _examples, mean_field_spins_reference)
