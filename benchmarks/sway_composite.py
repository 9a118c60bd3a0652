# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Write a copy of a CDnet-style folder whose left part sways slowly, as branches in wind.

A phantom check for rules that lower a pixel's noise level: the left
``--share`` of every frame is displaced by a smooth random field (at most
``--amplitude`` pixels, two sinusoids of ``--period`` seconds at 30 frames/s,
the vertical part half the horizontal), so textured edges there move back and
forth slowly while the ground truth stays as it was (a person in the region
moves with it by at most the amplitude). Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/sway_composite.py ../shared/data/sbi_HumanBody2 \
        /tmp/sway/sbi_HumanBody2_sw
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/eval_sequences.py \
        /tmp/sway/sbi_HumanBody2_sw

The output is never part of the repository (the frames are the shared data's).
"""

import argparse
from pathlib import Path

import cv2
from dgmod_ros.evaluation import write_composite
import numpy as np

FPS = 30.0


def sway_field(shape, share, seed=0):
    """Return the displacement pattern (rows, cols) float32 in [-1, 1] and the region's weight."""
    rows, cols = shape
    rng = np.random.default_rng(seed)
    field = cv2.GaussianBlur(rng.normal(0, 1, (rows, cols)).astype(np.float32), (0, 0), 12)
    field /= np.abs(field).max()
    region = np.zeros((rows, cols), np.float32)
    region[:, :int(cols * share)] = 1
    return field, cv2.GaussianBlur(region, (0, 0), 5)


def swayed(image, field, region, index, period, amplitude):
    """Return ``image`` displaced at frame ``index`` by ``field`` where ``region`` weighs."""
    rows, cols = image.shape[:2]
    phase = 2 * np.pi * index / (FPS * period)
    shift = amplitude * region * (np.sin(phase) * field
                                  + 0.5 * np.sin(2.3 * phase + 1) * np.roll(field, 40, axis=1))
    shift = shift.astype(np.float32)
    y, x = np.mgrid[0:rows, 0:cols].astype(np.float32)
    return cv2.remap(image, x + shift, y + 0.5 * shift, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REFLECT)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('source', type=Path)
    parser.add_argument('out', type=Path)
    parser.add_argument('--period', type=float, default=2.0, help='seconds')
    parser.add_argument('--amplitude', type=float, default=3.0, help='pixels')
    parser.add_argument('--share', type=float, default=1 / 3, help='of the width, from the left')
    args = parser.parse_args(argv)
    field = region = None

    def transform(index, image):
        nonlocal field, region
        if field is None:
            field, region = sway_field(image.shape[:2], args.share)
        return swayed(image, field, region, index, args.period, args.amplitude)

    write_composite(args.source, args.out, transform)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
