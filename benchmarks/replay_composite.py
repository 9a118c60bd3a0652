# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Write a CDnet-style copy of a folder in which a stretch of frames plays forward and back for long.

A phantom check for long runs. The dev clips last 3 to 60 s; a robot's
camera runs for hours, and what a detector holds out of its window over
minutes can feed on itself (docs/results.md: a plant's flicker that the
masks once called foreground grew into a phantom over a minute). This copy
plays the frames before ``--start`` once, then frames ``--start`` to
``--end`` forward, backward, forward... until the copy holds ``--frames``
frames, then, after a forward pass, the frames after ``--end`` once. Every
frame is a real one, with its own noise, light and ground truth (a person
seated in the stretch stays seated for as long as it plays). The scored
range starts at the first frame the source scores. Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/replay_composite.py \
        ../shared/data/sbi_Candela_m1.10 /tmp/replay/sbi_Candela_m1.10 --start 110 --end 285
    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. .venv/bin/python benchmarks/eval_sequences.py \
        /tmp/replay/sbi_Candela_m1.10

The output is never part of the repository (the frames are the shared data's).
"""

import argparse
from pathlib import Path
import shutil

from dgmod_ros.evaluation import load_dataset


def replay_order(count, start, end, frames):
    """
    Return the source indices (0-based) of the copy's frames, in order.

    Indices below ``start`` once, then ``start``..``end`` forward and back
    until at least ``frames`` are listed, ending on a forward pass, then the
    indices after ``end`` once (``count`` frames in the source).
    """
    if not 0 <= start < end < count:
        raise ValueError(f'need 0 <= start < end < {count}, got {start} and {end}')
    forward = list(range(start, end + 1))
    order = list(range(start))
    passes = 0
    while len(order) < frames or passes % 2 == 0:      # then ends on a forward pass
        order += forward if passes % 2 == 0 else forward[::-1]
        passes += 1
    return order + list(range(end + 1, count))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('source', type=Path)
    parser.add_argument('out', type=Path)
    parser.add_argument('--start', type=int, required=True,
                        help='first frame of the replayed stretch (0-based)')
    parser.add_argument('--end', type=int, required=True,
                        help='last frame of the replayed stretch (0-based)')
    parser.add_argument('--frames', type=int, default=2000,
                        help='frames in the copy before the frames after --end (about 67 s '
                             'at 30 frames/s)')
    args = parser.parse_args(argv)
    dataset = load_dataset(args.source)
    inputs = sorted((args.source / 'input').iterdir())
    order = replay_order(len(inputs), args.start, args.end, args.frames)
    for folder in ('input', 'groundtruth'):
        (args.out / folder).mkdir(parents=True, exist_ok=True)
    for position, index in enumerate(order, start=1):
        shutil.copy(inputs[index], args.out / 'input' / f'in{position:06d}{inputs[index].suffix}')
        shutil.copy(dataset.truths[index], args.out / 'groundtruth'
                    / f'gt{position:06d}{dataset.truths[index].suffix}')
    scored = next(p for p, index in enumerate(order, start=1) if index >= dataset.first)
    (args.out / 'temporalROI.txt').write_text(f'{scored} {len(order)}\n')
    if (args.source / 'ROI.bmp').exists():
        shutil.copy(args.source / 'ROI.bmp', args.out / 'ROI.bmp')
    print(f'{args.out}: {len(order)} frames')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
