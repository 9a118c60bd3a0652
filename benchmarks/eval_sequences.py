# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Score the detector on the dev sequences and the scenario suite: CDnet F and the planner's view.

Runs :func:`dgmod_ros.sequence.results` (the node's code path in stream mode)
with the package defaults, changed by ``--set name=value``, over every frame
of each dataset (the seven dev sequences by default), scores the temporal ROI
CDnet-style, writes the masks (to ``--masks DIR`` or a scratch folder) and
runs ``../shared/tools/object_recall.py`` on them (person recall, false blobs
per frame); the published background is scored where people were and the
place behind them has been seen
(:class:`~dgmod_ros.core.metrics.BackgroundPersonCounts`). ``--scenarios
DIR`` adds the scenario suite (:mod:`dgmod_ros.scenarios`), written to
``DIR`` first where it is not there yet; ``--scenarios-only`` scores only it.
``--max-frames N`` feeds each dataset up to its first scored frame plus ``N``
frames (a cheap run). Prints one line per dataset and the mean F.

Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/eval_sequences.py [DATASET ...]
        [--mode stream|batch] [--set decision=global --set memory_spacing=1 ...]
        [--scenarios out/scenarios [--scenarios-only] [--seed 0] [--duration-scale 1.0]]
        [--max-frames N] [--masks out/masks] [--json out/scores.json]
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import cv2
from dgmod_ros import config
from dgmod_ros.core.metrics import BackgroundPersonCounts, ConfusionCounts
from dgmod_ros.evaluation import load_dataset
from dgmod_ros.inputs import read_frames
from dgmod_ros.sequence import results
import numpy as np

DATA = Path(os.environ.get('DGMOD_DATA', Path(__file__).resolve().parents[2] / 'shared' / 'data'))
SEQUENCES = ('sbi_IBMtest2', 'sbi_CAVIAR2', 'sbi_CAVIAR1', 'sbi_Candela_m1.10', 'cdnet_highway',
             'sbi_HumanBody2', 'sbi_CaVignal')
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


def score_dataset(path, values, mode, masks_dir=None, max_frames=None):
    """
    Run one dataset; return a dict of its scores.

    With ``masks_dir`` the masks are written there (one folder per dataset) and
    ``object_recall.py`` adds person recall and false blobs per frame. With
    ``max_frames`` only the frames up to the first scored one plus
    ``max_frames`` are fed and scored.
    """
    dataset = load_dataset(path)
    frames = list(read_frames(dataset.path))
    last = dataset.last
    if max_frames is not None:
        frames = frames[:dataset.first + max_frames]
        last = min(last, len(frames) - 1)
    counts = ConfusionCounts()
    started = time.perf_counter()
    out = None
    if masks_dir is not None:
        out = Path(masks_dir) / dataset.name
        out.mkdir(parents=True, exist_ok=True)
        for stale in out.glob('bin*.png'):
            stale.unlink()
    behind = BackgroundPersonCounts()
    for frame, mask, background, _ in results(frames, values, mode):
        if background is not None:      # published before the scored frames too
            behind.background = background
        inside = dataset.first <= frame.index <= last
        if inside:
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(mask, truth, dataset.roi)
            image = frame.image[..., ::-1] if frame.channel_order == 'bgr' else frame.image
            behind.add(frame.index, image, truth, roi=None if dataset.roi is None
                       else dataset.roi > 0)
        if out is not None and inside:
            cv2.imwrite(str(out / mask_name(dataset, frame.index)), mask)
    seconds = time.perf_counter() - started
    row = {'dataset': dataset.name, 'precision': counts.precision, 'recall': counts.recall,
           'fmeasure': counts.fmeasure, 'frames': len(frames),
           'scored_frames': last - dataset.first + 1,
           'ms_per_frame': 1000 * seconds / len(frames),
           'background_wrong_behind': behind.wrong_share,
           'background_wrong_behind_late': behind.late_wrong_share}
    if out is not None and RECALL_TOOL.is_file():
        report = subprocess.run([sys.executable, str(RECALL_TOOL), str(dataset.path), str(out),
                                 '--json'], capture_output=True, text=True, check=True)
        recall = json.loads(report.stdout)
        recall['recall_frames'] = recall.pop('frames')
        row.update(recall)
    return row


def scenario_folders(folder, seed=0, duration_scale=1.0):
    """Return the suite's folders under ``folder``, writing those not there yet."""
    from dgmod_ros.scenarios import build_scenario, load_material, SCENARIO_NAMES, write_sequence
    folder = Path(folder)
    missing = [n for n in SCENARIO_NAMES if not (folder / n / 'temporalROI.txt').is_file()]
    if missing:
        material = load_material(DATA)
        for name in missing:
            write_sequence(build_scenario(name, material, seed, duration_scale), folder / name)
    return [folder / n for n in SCENARIO_NAMES]


def format_row(row):
    """Return one dataset's line of the table."""
    extra = ''
    if 'person_recall' in row:
        extra = (f"  person recall {row['person_recall']:.3f}  false blobs/frame "
                 f"{row['false_blobs_per_frame']:.2f}")
    late = row['background_wrong_behind_late']
    extra += f"  background wrong behind people {row['background_wrong_behind']:.3f}"
    extra += '' if late is None else f' (after 60 s {late:.3f})'
    return (f"{row['dataset']:20s} Pr {row['precision']:.3f} Re {row['recall']:.3f} "
            f"F {row['fmeasure']:.3f}  {row['ms_per_frame']:.1f} ms/frame{extra}")


def main(argv=None):
    """Parse the command line, score every dataset, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('datasets', nargs='*')
    parser.add_argument('--mode', default='stream', choices=('stream', 'batch'))
    parser.add_argument('--set', action='append', default=[], metavar='NAME=VALUE')
    parser.add_argument('--scenarios', default=None, metavar='DIR',
                        help='also score the scenario suite (written to DIR if not there)')
    parser.add_argument('--scenarios-only', action='store_true')
    parser.add_argument('--seed', type=int, default=0, help="the scenarios' seed")
    parser.add_argument('--duration-scale', type=float, default=1.0,
                        help="the scenarios' lingering and still spans (1.0: the 60 s stand)")
    parser.add_argument('--max-frames', type=int, default=None)
    parser.add_argument('--masks', default=None)
    parser.add_argument('--json', default=None)
    args = parser.parse_args(argv)
    values = dict(config.DEFAULTS)
    for item in args.set:
        name, text = item.split('=', 1)
        values[name] = config.parse_value(name, text)
    paths = [] if args.scenarios_only else (args.datasets or [DATA / s for s in SEQUENCES])
    if args.scenarios:
        paths += scenario_folders(args.scenarios, args.seed, args.duration_scale)
    rows = []
    with tempfile.TemporaryDirectory(prefix='dgmod-masks-') as scratch:
        for path in paths:
            row = score_dataset(path, values, args.mode, args.masks or scratch, args.max_frames)
            rows.append(row)
            print(format_row(row), flush=True)
    print(f"mean F {np.mean([r['fmeasure'] for r in rows]):.3f}  mode {args.mode}  "
          f"set {' '.join(args.set) or '(defaults)'}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(rows, indent=2))


if __name__ == '__main__':
    main()
