# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Write the scenario suite in the shared data's layout.

Usage::

    python -m dgmod_ros.scenarios --out out/scenarios --seed 0
        [--data ../shared/data] [--duration-scale 1.0] [--only stops --only crossing]
"""

import argparse
import json
import os
from pathlib import Path
import sys
import time

from .layout import describe, write_sequence
from .material import load_material
from .suite import build_scenario, SCENARIO_NAMES

DEFAULT_DATA = Path(os.environ.get('DGMOD_DATA', '../shared/data'))


def main(argv=None):
    """Parse the command line, build the scenarios, write them; return 0 (2 on bad data)."""
    parser = argparse.ArgumentParser(prog='python -m dgmod_ros.scenarios',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--out', required=True, help='folder; one sub-folder per scenario')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--data', default=str(DEFAULT_DATA),
                        help='the shared sequences (default $DGMOD_DATA or ../shared/data)')
    parser.add_argument('--duration-scale', type=float, default=1.0,
                        help='shorten the lingering and still spans (1.0: the 60 s stand)')
    parser.add_argument('--only', action='append', choices=SCENARIO_NAMES, default=None,
                        help='build only this scenario (repeatable)')
    args = parser.parse_args(argv)
    if args.duration_scale <= 0:
        parser.error('--duration-scale must be positive')
    try:
        material = load_material(args.data)
    except (FileNotFoundError, OSError) as error:
        print(f'error: {error}', file=sys.stderr)
        return 2
    for name in args.only or SCENARIO_NAMES:
        started = time.perf_counter()
        scenario = build_scenario(name, material, args.seed, args.duration_scale)
        folder = write_sequence(scenario, Path(args.out) / name)
        print(f'{folder}: {len(scenario)} frames, {time.perf_counter() - started:.0f} s  '
              f'{json.dumps(describe(scenario)["people"])}', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
