# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Write a copy of a CDnet-style folder as a block codec with conditional replenishment records it.

A phantom check for low-rate recordings. The clips of the PBI set (CaVignal
among the dev clips) repeat most pixels exactly from frame to frame: in
CaVignal 83 % of the colour pixels are bit for bit those of the frame
before, and the rest change in 8 x 8 blocks by a few grey levels wherever
the encoder re-encoded a block (around whoever moves, and here and there).
A noise level read as a median then reads the one-grey-level floor, and
every re-encoded block is a change of many levels. This copy makes any
clip such a recording: each 8 x 8 block of a frame whose mean absolute
difference from the block last written is below ``--threshold`` grey
levels is that block again, exactly; the others are the frame's JPEG
(``--quality``) there. The ground truth stays as it was. Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/codec_composite.py ../shared/data/sbi_HumanBody2 \
        /tmp/codec/sbi_HumanBody2
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/eval_sequences.py \
        /tmp/codec/sbi_HumanBody2

The output is never part of the repository (the frames are the shared data's).
"""

import argparse
from pathlib import Path

import cv2
from dgmod_ros.evaluation import write_composite
import numpy as np

BLOCK = 8


def block_means(image):
    """Return the mean of each ``BLOCK`` x ``BLOCK`` block (all channels) of an (h, w, C) image."""
    rows, cols = image.shape[:2]
    padded = np.pad(image.astype(np.float32),
                    ((0, -rows % BLOCK), (0, -cols % BLOCK), (0, 0)), mode='edge')
    blocks = padded.reshape(padded.shape[0] // BLOCK, BLOCK, padded.shape[1] // BLOCK, BLOCK, -1)
    return blocks.mean(axis=(1, 3, 4))


def replenished(previous, frame, threshold, quality):
    """
    Return ``frame`` as the codec writes it after ``previous`` (None: the first frame).

    Blocks whose mean absolute difference from ``previous`` is below
    ``threshold`` grey levels are copied from ``previous``; the others are the
    frame's JPEG at ``quality``. Both images are (h, w, 3) uint8.
    """
    encoded = cv2.imdecode(cv2.imencode('.jpg', frame, [cv2.IMWRITE_JPEG_QUALITY, quality])[1],
                           cv2.IMREAD_COLOR)
    if previous is None:
        return encoded
    difference = np.abs(frame.astype(np.int16) - previous.astype(np.int16))
    moved = block_means(difference) >= threshold
    rows, cols = frame.shape[:2]
    fresh = np.kron(moved, np.ones((BLOCK, BLOCK), dtype=bool))[:rows, :cols]
    return np.where(fresh[:, :, None], encoded, previous)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('source', type=Path)
    parser.add_argument('out', type=Path)
    parser.add_argument('--threshold', type=float, default=4.0,
                        help='mean absolute difference (grey levels) that re-encodes a block')
    parser.add_argument('--quality', type=int, default=90,
                        help='JPEG quality of a re-encoded block')
    args = parser.parse_args(argv)
    written = None

    def transform(index, image):
        nonlocal written
        written = replenished(written, image, args.threshold, args.quality)
        return written

    write_composite(args.source, args.out, transform, suffix='.png')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
