# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Fingerprint the detector's output: a sha256 of every mask and background, per dev sequence.

A refactor that keeps behaviour keeps these digests. Runs
:func:`dgmod_ros.sequence.results` (the node's code path) with the package
defaults over each sequence (``--max-frames N`` for the first ``N``) and
prints, per sequence, one digest of the masks and one of the backgrounds,
byte for byte. ``--json F`` writes them; ``--against F`` compares with a file
written before and exits 1 on any difference.

Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/fingerprint.py [--mode stream|batch]
        [--max-frames N] [--json out/fp.json] [--against out/fp_before.json] [DATASET ...]
"""

import argparse
import hashlib
import json
import sys

from dgmod_ros import config
from dgmod_ros.evaluation import load_dataset
from dgmod_ros.inputs import read_frames
from dgmod_ros.sequence import results
import numpy as np

sys.path.insert(0, str(__import__('pathlib').Path(__file__).resolve().parent))
from eval_sequences import DATA, SEQUENCES  # noqa: E402, I100


def fingerprint(name, mode, max_frames):
    """Return ``{'frames', 'masks', 'backgrounds'}`` digests of one sequence."""
    dataset = load_dataset(DATA / name)
    frames = list(read_frames(dataset.path))
    if max_frames is not None:
        frames = frames[:max_frames]
    values = dict(config.DEFAULTS)
    masks, backgrounds = hashlib.sha256(), hashlib.sha256()
    count = 0
    for frame, mask, background, _ in results(frames, values, mode):
        masks.update(np.ascontiguousarray(mask).tobytes())
        if background is not None:
            backgrounds.update(str(count).encode())
            backgrounds.update(np.ascontiguousarray(background).tobytes())
        count += 1
    return {'frames': count, 'masks': masks.hexdigest()[:16],
            'backgrounds': backgrounds.hexdigest()[:16]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('datasets', nargs='*', default=list(SEQUENCES))
    parser.add_argument('--mode', default='stream', choices=('stream', 'batch'))
    parser.add_argument('--max-frames', type=int, default=None)
    parser.add_argument('--json', default=None)
    parser.add_argument('--against', default=None)
    args = parser.parse_args()
    found = {}
    for name in args.datasets:
        found[name] = fingerprint(name, args.mode, args.max_frames)
        print(name, found[name], flush=True)
    if args.json:
        with open(args.json, 'w') as out:
            json.dump(found, out, indent=1, sort_keys=True)
    if args.against:
        with open(args.against) as before:
            expected = json.load(before)
        differ = [n for n in found if expected.get(n) != found[n]]
        print('identical' if not differ else f'DIFFERENT: {differ}')
        return 1 if differ else 0
    return 0


if __name__ == '__main__':
    sys.exit(main())
