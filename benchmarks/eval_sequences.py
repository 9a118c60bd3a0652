# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Score the detector on the shared sequences: CDnet Pr, Re, F and the planner's view.

Runs :func:`dgmod_ros.sequence.results` (the node's code path in stream mode)
with the package defaults, changed by ``--set name=value``, over every frame
of each dataset, scores the temporal ROI CDnet-style and, with ``--masks DIR``,
writes the masks and runs ``../shared/tools/object_recall.py`` on them (person
recall, false blobs per frame). Prints one line per dataset and the mean F.

Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/eval_sequences.py [DATASET ...]
        [--mode stream|batch] [--set decision=global --set memory_spacing=1 ...]
        [--masks out/masks] [--json out/scores.json]
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import time

import cv2
from dgmod_ros import config
from dgmod_ros.core.metrics import ConfusionCounts
from dgmod_ros.evaluation import load_dataset
from dgmod_ros.inputs import read_frames
from dgmod_ros.sequence import results
import numpy as np

DATA = Path(os.environ.get('DGMOD_DATA', Path(__file__).resolve().parents[2] / 'shared' / 'data'))
SEQUENCES = ('sbi_IBMtest2', 'sbi_CAVIAR2', 'sbi_CAVIAR1', 'sbi_Candela_m1.10', 'cdnet_highway')
RECALL_TOOL = DATA.parent / 'tools' / 'object_recall.py'


def mask_name(dataset, index):
    """
    Name frame ``index``'s mask with its ground truth's number (``gt000000`` -> ``bin000000``).

    ``object_recall.py`` pairs masks and truths by number, and the SBI sequences
    number from 0 while CDnet numbers from 1: a name from the frame's position
    compared each SBI mask with the next frame's truth.
    """
    if index < len(dataset.truths):
        digits = ''.join(c for c in dataset.truths[index].stem if c.isdigit())
        if digits:
            return f'bin{digits}.png'
    return f'bin{index + 1:06d}.png'


def score_dataset(path, values, mode, masks_dir=None):
    """Run one dataset; return a dict of its scores."""
    dataset = load_dataset(path)
    frames = list(read_frames(dataset.path))
    counts = ConfusionCounts()
    started = time.perf_counter()
    out = None
    if masks_dir is not None:
        out = Path(masks_dir) / dataset.name
        out.mkdir(parents=True, exist_ok=True)
    for frame, mask, _, _ in results(frames, values, mode):
        if dataset.first <= frame.index <= dataset.last:
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(mask, truth, dataset.roi)
        if out is not None:
            cv2.imwrite(str(out / mask_name(dataset, frame.index)), mask)
    seconds = time.perf_counter() - started
    row = {'dataset': dataset.name, 'precision': counts.precision, 'recall': counts.recall,
           'fmeasure': counts.fmeasure, 'ms_per_frame': 1000 * seconds / len(frames)}
    if out is not None and RECALL_TOOL.is_file():
        report = subprocess.run([sys.executable, str(RECALL_TOOL), str(dataset.path), str(out),
                                 '--json'], capture_output=True, text=True, check=True)
        row.update(json.loads(report.stdout))
    return row


def main(argv=None):
    """Parse the command line, score every dataset, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('datasets', nargs='*', default=[str(DATA / s) for s in SEQUENCES])
    parser.add_argument('--mode', default='stream', choices=('stream', 'batch'))
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE')
    parser.add_argument('--masks', default=None)
    parser.add_argument('--json', default=None)
    args = parser.parse_args(argv)
    values = dict(config.DEFAULTS)
    for item in args.set:
        name, text = item.split('=', 1)
        values[name] = config.parse_value(name, text)
    rows = []
    for path in args.datasets:
        row = score_dataset(path, values, args.mode, args.masks)
        rows.append(row)
        extra = ''
        if 'person_recall' in row:
            extra = (f"  person recall {row['person_recall']:.3f}  false blobs/frame "
                     f"{row['false_blobs_per_frame']:.2f}")
        print(f"{row['dataset']:20s} Pr {row['precision']:.3f} Re {row['recall']:.3f} "
              f"F {row['fmeasure']:.3f}  {row['ms_per_frame']:.1f} ms/frame{extra}", flush=True)
    print(f"mean F {np.mean([r['fmeasure'] for r in rows]):.3f}  mode {args.mode}  "
          f"set {' '.join(args.set) or '(defaults)'}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == '__main__':
    main()
