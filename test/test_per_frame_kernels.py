# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The per-frame path's compiled kernels give their numpy references' results bit for bit."""

from dgmod_ros.core.streaming import mean_field_kernel
from dgmod_ros.core.streaming.coherence import mean_field_mask, mean_field_mask_reference
import numpy as np
import pytest


def _field_case(rng, rows, cols, scalar_noise, nan=False):
    """Return distances and noise levels of a frame with blobs, noise and maybe non-finite pixels."""
    noise = (float(rng.uniform(0.002, 0.05)) if scalar_noise
             else rng.uniform(0.005, 0.05, rows * cols).astype(np.float32))
    z = np.abs(rng.normal(0, 2.5, (rows, cols))).astype(np.float32)
    for _ in range(3):                                  # people: regions far over k
        r, c = rng.integers(0, rows), rng.integers(0, cols)
        z[r:r + rng.integers(1, 12), c:c + rng.integers(1, 12)] += rng.uniform(3, 15)
    distance = (z.ravel() * noise).astype(np.float32)
    if nan:
        distance[rng.integers(0, distance.size, 2)] = np.nan
    return distance, noise


@pytest.mark.parametrize('seed', range(12))
def test_mean_field_kernel_gives_the_reference_masks(seed):
    rng = np.random.default_rng(seed)
    rows, cols = int(rng.integers(1, 70)), int(rng.integers(1, 90))
    nan = seed % 4 == 1             # the kernel hands these to the reference
    distance, noise = _field_case(rng, rows, cols, scalar_noise=seed % 3 == 0, nan=nan)
    k, beta = float(rng.choice([6.0, 4.5, 3.0])), float(rng.choice([2.0, 0.7, 1.3, 0.0]))
    for sweeps, radius in ((5, 2), (2, 1), (3, 3)):
        spins = mean_field_kernel.mean_field_spins(distance, noise, k, beta, rows, cols, sweeps,
                                                   radius, 3.0, 50.0)
        assert (spins is None) == nan
        got = mean_field_mask(distance, noise, k, beta, (rows, cols, 3), sweeps, radius)
        expected = mean_field_mask_reference(distance, noise, k, beta, (rows, cols, 3), sweeps,
                                              radius)
        assert got.dtype == np.uint8 and got.shape == (rows, cols)
        assert np.array_equal(got, expected)


def test_mean_field_kernel_hands_numpy_float64_scalars_to_the_reference():
    # numpy computes in float64 with a numpy float64 k: the kernel does not reproduce that.
    distance = np.ones(12, np.float32)
    assert mean_field_kernel.mean_field_spins(distance, 0.1, np.float64(6.0), 2.0, 3, 4, 5, 2,
                                              3.0, 50.0) is None
    assert mean_field_kernel.mean_field_spins(distance, np.ones(12), 6.0, 2.0, 3, 4, 5, 2,
                                              3.0, 50.0) is None


def test_numpy_tanh_is_exactly_one_beyond_the_saturation_bound():
    # The kernel writes +-1 without calling tanh beyond SATURATED: numpy's float32 tanh must agree.
    beyond = np.linspace(mean_field_kernel.SATURATED, 60.0, 2_000_001, dtype=np.float32)
    assert np.all(np.tanh(beyond) == 1.0)
    assert np.all(np.tanh(-beyond) == -1.0)


def test_a_tiny_or_nan_spin_sends_the_field_to_the_reference():
    spin = np.ones((2, 2), np.float32)
    index = np.array([0, 3], np.int64)
    assert mean_field_kernel._scatter(index, np.array([0.5, 0.0], np.float32), 2, spin)
    assert not mean_field_kernel._scatter(index, np.array([0.5, 1e-9], np.float32), 2, spin)
    assert not mean_field_kernel._scatter(index, np.array([np.nan, 1.0], np.float32), 2, spin)
