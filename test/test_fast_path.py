# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The fast path's compiled l1 projection against its numpy formulation."""

from dgmod_ros.core.streaming.fast_path import (background_basis, fit_step, robust_projection,
                                                robust_projection_reference, sampled_basis)
import numpy as np
import pytest


def _frame_and_basis(rank, seed=4, n=3000, channels=3):
    rng = np.random.default_rng(seed)
    ramp = np.linspace(0.2, 0.8, n, dtype=np.float32)
    window = (ramp[None, :, None] * rng.uniform(0.8, 1.2, (channels, 1, 20))
              + 0.01 * rng.standard_normal((channels, n, 20))).astype(np.float32)
    basis = np.zeros((channels, n, rank), dtype=np.float32)
    for channel in range(channels):
        own = background_basis(window[channel], rank)
        basis[channel, :, :own.shape[1]] = own
    frame = 1.1 * window[:, :, -1]
    frame[:, 1000:1300] = 0.95          # a person: the l1 fit must ignore it
    return basis, frame.astype(np.float32), ramp


@pytest.mark.parametrize('rank', [1, 2, 3])
def test_compiled_projection_equals_numpy(rank):
    basis, frame, _ = _frame_and_basis(rank)
    assert np.allclose(robust_projection(basis, frame),
                       robust_projection_reference(basis, frame), atol=1e-5)


def test_projection_ignores_the_foreground_and_takes_the_gain():
    basis, frame, ramp = _frame_and_basis(2)
    fitted = robust_projection(basis, frame)
    background = np.delete(np.arange(frame.shape[1]), np.arange(1000, 1300))
    # The frame is the window's last column times 1.1 outside the person.
    assert np.abs(fitted[:, background] - frame[:, background]).max() < 0.05
    assert np.abs(fitted[:, 1000:1300] - 0.95).min() > 0.2


def test_projection_with_a_zero_padded_channel_basis():
    # A channel whose background has lower rank than the others keeps zero columns.
    basis, frame, _ = _frame_and_basis(2)
    basis[1, :, 1] = 0.0
    assert np.allclose(robust_projection(basis, frame),
                       robust_projection_reference(basis, frame), atol=1e-5)


@pytest.mark.parametrize('rank', [1, 2, 3])
def test_sampled_fit_equals_numpy(rank):
    # 3000 pixels, at most 700 weighed: every 4th pixel.
    basis, frame, _ = _frame_and_basis(rank)
    assert np.allclose(robust_projection(basis, frame, fit_pixels=700),
                       robust_projection_reference(basis, frame, fit_pixels=700), atol=1e-5)
    # A solve forms the sampled basis once for every frame until the next.
    kept = sampled_basis(basis, fit_pixels=700)
    assert kept.shape[1] == 750 and kept.flags.c_contiguous
    assert np.array_equal(robust_projection(basis, frame, fit_pixels=700, fit_basis=kept),
                          robust_projection(basis, frame, fit_pixels=700))


def test_sampled_fit_projects_every_pixel_as_the_full_fit_does():
    basis, frame, _ = _frame_and_basis(2, n=12000)
    frame[:, 4000:5200] = 0.95          # the person scaled with the frame
    full = robust_projection(basis, frame, fit_pixels=12000)
    sampled = robust_projection(basis, frame, fit_pixels=1000)     # every 12th pixel
    assert fit_step(12000, 1000) == 12 and fit_step(12000, 12000) == 1
    # Measured: at most 0.0026 apart (the frame's noise is 0.01), against the
    # person's 0.4 and more.
    assert np.abs(sampled - full).max() < 0.005
    assert np.abs(sampled[:, 4000:5200] - 0.95).min() > 0.2


def test_a_person_covering_much_of_the_view_is_left_out_of_the_starting_fit():
    # A dark person over 45 % of the pixels pulls the least-squares start
    # towards them, and three sweeps from there leave the whole frame off
    # its background; the previous frame's foreground left out of the fit,
    # it is the frame's gain again.
    basis, frame, _ = _frame_and_basis(2)
    person = np.zeros(frame.shape[1], dtype=bool)
    person[600:1950] = True
    frame[:, person] = 0.02
    outside = ~person
    pulled = np.abs(robust_projection(basis, frame) - frame)[:, outside]
    fitted = robust_projection(basis, frame, left_out=person)
    assert np.abs(fitted - frame)[:, outside].max() < 0.05
    assert pulled.max() > 2 * np.abs(fitted - frame)[:, outside].max()
    # Too few pixels left to fix a fit: the start of the whole frame.
    everything = np.ones_like(person)
    assert np.array_equal(robust_projection(basis, frame, left_out=everything),
                          robust_projection(basis, frame))
