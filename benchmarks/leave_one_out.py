# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Leave-one-sequence-out check of the defaults chosen on data.

For each parameter of :data:`GRID` (the thresholds, counts and spacings whose
defaults were chosen by scoring the dev sequences) it runs the default and
its neighbours on each of the seven dev sequences (stream mode, as the node
runs), caching every (parameter, value, sequence) score in a JSON file, so a
run only computes what the cache lacks and an interrupted run resumes. Then,
for each held-out sequence, it picks the value with the best mean F on the
other six and reports the F that value gives on the held-out one.

Printed per parameter: the chosen value and its held-out F for each sequence,
the leave-one-out mean (each sequence scored with a value chosen without it)
beside the all-seven mean (the value chosen on all seven, scored on the same
seven), the default's all-seven mean, and a flag where the default helps
only where it was chosen:

* ``LOO GAP``: the leave-one-out mean is more than ``--gap`` below the
  all-seven mean of the all-seven choice (the choice is fitted to clips);
* ``FEW WINS``: the default is the all-seven choice but a neighbour beats it
  on most sequences (its lead comes from a minority of clips);
* ``NOT CHOSEN``: the value chosen on all seven is not the default.

Cheap runs: ``--params``, ``--sequences``, ``--max-frames N`` (each sequence
fed up to its first scored frame plus ``N`` frames; the cache keys include
``N``). Scores are tagged with a fingerprint of the code that makes the masks
(:func:`mask_code`) and the commit; a run with other mask code recomputes
them (``--any-code`` reuses them).

Usage::

    PYTHONPATH=. .venv/bin/python benchmarks/leave_one_out.py [--params pixel_k still_frames]
        [--sequences sbi_IBMtest2 ...] [--max-frames 300] [--cache out/loo_cache.json]
        [--report-only] [--detail] [--json out/loo.json]
"""

import argparse
import hashlib
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

from dgmod_ros import config
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_sequences import DATA, score_dataset, SEQUENCES  # noqa: E402, I100

# Defaults chosen by scoring the dev sequences (docs/results.md), each with the
# default and its neighbours (about a factor 1.5-2 either way for counts and
# spacings, one step for thresholds).
GRID = {
    'pixel_k': (4.5, 6.0, 7.5),
    'still_frames': (10, 15, 25),
    'line_pixels': (0, 36, 64, 100),
    'fill_holes': (False, True),
    'doubtful_floor': (0.0, 0.5, 1.0),
    'memory_spacing': (5, 10, 20),
    'memory_columns': (5, 10, 15),
    'warm_start': (False, True),
    'absorb_frames': (2700, 5400, 10800),
    'moving_texture_k': (1.5, 2.0, 3.0),
    'moving_texture_bits': (8, 12, 16),
    'texture_bits': (6, 8, 10),
    'mrf_beta': (1.0, 2.0, 3.0),
}
# Not in the grid: median_size (with mrf_beta > 0 the Potts field decides and
# the median filter is not applied: 3 and 5 gave the same masks on the five
# sequences measured, docs/results.md).
REPO = Path(__file__).resolve().parents[1]
TIE = 1e-4      # mean F differences below this choose the default


def mask_code(root=REPO):
    """
    Return a fingerprint of the code that makes the masks (sha1 of its files).

    Every module of the package except the scoring (``core/metrics.py``,
    ``evaluation.py``), the scenarios and the ROS layer: a cached score is
    reused while these files are unchanged, whatever else was committed.
    """
    package = Path(root) / 'dgmod_ros'
    skip = {'core/metrics.py', 'evaluation.py', 'detector_node.py', 'depth_outputs.py',
            'cli.py', 'transport.py', 'solve_worker.py', 'stamp_pairing.py', 'stats.py'}
    digest = hashlib.sha1()
    for path in sorted(package.rglob('*.py')):
        name = path.relative_to(package).as_posix()
        if name in skip or name.startswith('scenarios/'):
            continue
        digest.update(name.encode() + b'\0' + path.read_bytes() + b'\0')
    return digest.hexdigest()[:12]


def commit(root=REPO):
    """Return the checkout's commit, for the record (``unknown`` outside git)."""
    try:
        return subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=root,
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return 'unknown'


def cache_key(name, value, sequence, max_frames):
    """Key of one score; the default of every parameter shares one key (one run)."""
    setting = 'defaults' if value == config.DEFAULTS[name] else f'{name}={value}'
    return f'{setting}|{sequence}|{max_frames or "all"}'


class ScoreCache:
    """The JSON file of scores, written after every new score."""

    def __init__(self, path, code, revision, any_code):
        self.path, self.code, self.revision = Path(path), code, revision
        self.any_code = any_code
        self.entries = json.loads(self.path.read_text()) if self.path.is_file() else {}

    def get(self, key):
        """Return a cached score or None (or one of other mask code, unless allowed)."""
        entry = self.entries.get(key)
        if entry is None or (entry.get('code') != self.code and not self.any_code):
            return None
        return entry

    def put(self, key, row):
        """Store one score and write the file (atomically: a stopped run keeps the rest)."""
        self.entries[key] = dict(row, code=self.code, commit=self.revision)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        scratch = self.path.with_suffix('.tmp')
        scratch.write_text(json.dumps(self.entries, indent=1, sort_keys=True))
        os.replace(scratch, self.path)


def run_grid(params, sequences, max_frames, cache, compute=True):
    """Return ``scores[name][value][sequence] = row`` from the cache, computing what it lacks."""
    scores = {}
    with tempfile.TemporaryDirectory(prefix='dgmod-loo-') as scratch:
        for name in params:
            for value in GRID[name]:
                for sequence in sequences:
                    key = cache_key(name, value, sequence, max_frames)
                    row = cache.get(key)
                    if row is None and compute:
                        values = dict(config.DEFAULTS, **{name: value})
                        started = time.perf_counter()
                        row = score_dataset(DATA / sequence, values, 'stream', scratch,
                                            max_frames)
                        cache.put(key, row)
                        print(f'  {key:45s} F {row["fmeasure"]:.4f}  '
                              f'{time.perf_counter() - started:.0f} s', flush=True)
                    if row is not None:
                        scores.setdefault(name, {}).setdefault(value, {})[sequence] = row
    return scores


def _choose(by_value, sequences, default):
    """Return the value with the best mean F over ``sequences`` (ties: the default)."""
    means = {v: np.mean([by_value[v][s]['fmeasure'] for s in sequences]) for v in by_value}
    best = max(means.values())
    if means.get(default, -1) >= best - TIE:
        return default
    return max(means, key=means.get)


def leave_one_out(name, by_value, sequences, gap):
    """Return one parameter's leave-one-out summary (a dict), or None if scores are missing."""
    complete = {v: r for v, r in by_value.items() if all(s in r for s in sequences)}
    default = config.DEFAULTS[name]
    if default not in complete or len(complete) < 2:
        return None
    held = {}
    for out in sequences:
        rest = [s for s in sequences if s != out]
        chosen = _choose(complete, rest, default)
        held[out] = (chosen, complete[chosen][out]['fmeasure'])
    everywhere = _choose(complete, sequences, default)
    mean_of = {v: float(np.mean([complete[v][s]['fmeasure'] for s in sequences]))
               for v in complete}
    loo_mean = float(np.mean([f for _, f in held.values()]))
    wins = sum(all(complete[default][s]['fmeasure'] >= complete[v][s]['fmeasure'] - TIE
                   for v in complete) for s in sequences)
    flags = []
    if loo_mean < mean_of[everywhere] - gap:
        flags.append('LOO GAP')
    if everywhere == default and wins < (len(sequences) + 1) // 2:
        flags.append('FEW WINS')
    if everywhere != default:
        flags.append('NOT CHOSEN')
    return {'parameter': name, 'default': default, 'values': sorted(complete),
            'held_out': {s: {'chosen': c, 'fmeasure': f} for s, (c, f) in held.items()},
            'loo_mean': loo_mean, 'all_seven_choice': everywhere,
            'all_seven_mean': mean_of[everywhere], 'default_mean': mean_of[default],
            'mean_by_value': {str(v): m for v, m in mean_of.items()},
            'default_wins': wins, 'flags': flags}


def short(sequence):
    """Short column name of a sequence."""
    return sequence.replace('sbi_', '').replace('cdnet_', '').replace('_m1.10', '')


def table(summaries, sequences):
    """Return the markdown table of the summaries."""
    head = ['parameter (default)'] + [short(s) for s in sequences] + [
        'LOO mean', 'all-seven mean (choice)', 'default mean', 'default wins', 'flags']
    lines = ['| ' + ' | '.join(head) + ' |', '|' + ' --- |' * len(head)]
    for summary in summaries:
        cells = [f"`{summary['parameter']}` ({summary['default']})"]
        for s in sequences:
            held = summary['held_out'][s]
            cells.append(f"{held['chosen']}: {held['fmeasure']:.4f}")
        cells += [f"{summary['loo_mean']:.4f}",
                  f"{summary['all_seven_mean']:.4f} ({summary['all_seven_choice']})",
                  f"{summary['default_mean']:.4f}",
                  f"{summary['default_wins']}/{len(sequences)}",
                  ', '.join(summary['flags']) or '-']
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def detail(summaries, scores, sequences):
    """Return the markdown table of F for every value on every sequence."""
    head = ['parameter', 'value'] + [short(s) for s in sequences] + ['mean']
    lines = ['| ' + ' | '.join(head) + ' |', '|' + ' --- |' * len(head)]
    for summary in summaries:
        name = summary['parameter']
        for value in summary['values']:
            f = [scores[name][value][s]['fmeasure'] for s in sequences]
            mark = ' (default)' if value == summary['default'] else ''
            lines.append(f'| `{name}` | {value}{mark} | ' + ' | '.join(f'{v:.4f}' for v in f)
                         + f' | {np.mean(f):.4f} |')
    return '\n'.join(lines)


def main(argv=None):
    """Parse the command line, fill the cache, print the leave-one-out table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--params', nargs='+', default=list(GRID), choices=list(GRID))
    parser.add_argument('--sequences', nargs='+', default=list(SEQUENCES))
    parser.add_argument('--max-frames', type=int, default=None)
    parser.add_argument('--cache', default='out/loo_cache.json')
    parser.add_argument('--any-code', action='store_true',
                        help='reuse cached scores measured with other mask code')
    parser.add_argument('--report-only', action='store_true',
                        help='compute nothing; report what the cache holds')
    parser.add_argument('--gap', type=float, default=0.005,
                        help='leave-one-out mean this far below the all-seven mean is flagged')
    parser.add_argument('--detail', action='store_true',
                        help='also print F for every value on every sequence')
    parser.add_argument('--json', default=None)
    args = parser.parse_args(argv)
    if len(args.sequences) < 3:
        parser.error('leave-one-out needs at least three sequences')
    code, revision = mask_code(), commit()
    cache = ScoreCache(args.cache, code, revision, args.any_code)
    print(f'commit {revision}, mask code {code}, cache {args.cache}, '
          f'max frames {args.max_frames or "all"}', flush=True)
    scores = run_grid(args.params, args.sequences, args.max_frames, cache,
                      compute=not args.report_only)
    summaries = [s for s in (leave_one_out(n, scores.get(n, {}), args.sequences, args.gap)
                             for n in args.params) if s is not None]
    missing = [n for n in args.params if n not in {s['parameter'] for s in summaries}]
    print(table(summaries, args.sequences))
    if args.detail:
        print()
        print(detail(summaries, scores, args.sequences))
    if summaries:
        print(f"mean over parameters: LOO {np.mean([s['loo_mean'] for s in summaries]):.4f}, "
              f"all-seven {np.mean([s['all_seven_mean'] for s in summaries]):.4f}, "
              f"defaults {summaries[0]['default_mean']:.4f}")
    if missing:
        print(f"not complete in the cache: {' '.join(missing)}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(summaries, indent=2))


if __name__ == '__main__':
    main()
