# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Frames per second of ``dgmod separate --mode stream`` on 300 frames (default 640 x 480).

Two inputs at ``--size``: the synthetic scene written as PNG files to a
temporary folder, and frames 470-769 of CDnet highway (JPEG, resized from
320 x 240) when ../shared/data is present. Default parameters. The figure is
report.json's ``fps`` (decoding, separation and writing included); the issue's
target is 60 frames/s at 640 x 480.

Usage (repo root): PYTHONPATH=. python benchmarks/bench_stream.py [--size 640x480] [--method dgmod]
"""

import argparse
from concurrent.futures import ThreadPoolExecutor
import json
from pathlib import Path
import shutil
import tempfile
import time

import cv2
from dgmod_ros import cli, config
from dgmod_ros.core.numba_setup import use_threads
from dgmod_ros.core.synthetic import synthetic_scene
from dgmod_ros.inputs import read_frames

HIGHWAY = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'cdnet_highway' / 'input'


def detector_rate(frames, values, threaded):
    """Return frames per second of the streaming detector on decoded frames."""
    detector = config.build_detector(values)
    with ThreadPoolExecutor(max_workers=1, initializer=use_threads,
                            initargs=(values['solve_threads'],)) as pool:
        started = time.perf_counter()
        for frame in frames:
            detector.process(frame.image, frame.channel_order, executor=pool if threaded else None)
        return len(frames) / (time.perf_counter() - started)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--method', default='dgmod')
    parser.add_argument('--size', default='640x480', help='WIDTHxHEIGHT of the input frames')
    args, extra = parser.parse_known_args(argv)
    width, height = (int(v) for v in args.size.lower().split('x'))
    work = Path(tempfile.mkdtemp(prefix='dgmod_bench_'))
    try:
        synthetic = work / 'synthetic'
        synthetic.mkdir()
        for index, frame in enumerate(synthetic_scene(n_frames=300,
                                                      shape=(height, width)).frames):
            bgr = cv2.cvtColor(frame, cv2.COLOR_RGB2BGR)
            cv2.imwrite(str(synthetic / f'{index:06d}.png'), bgr)
        inputs = {f'synthetic {width}x{height} PNG': synthetic}
        if HIGHWAY.is_dir():
            highway = work / 'highway'
            highway.mkdir()
            for path in sorted(HIGHWAY.iterdir())[469:769]:
                image = cv2.imread(str(path))
                if image.shape[:2] != (height, width):
                    image = cv2.resize(image, (width, height), interpolation=cv2.INTER_LINEAR)
                cv2.imwrite(str(highway / path.name), image)
            inputs[f'CDnet highway 470-769 JPEG at {width}x{height}'] = highway
        for name, folder in inputs.items():
            out = work / f'out_{folder.name}'
            cli.main(['separate', str(folder), '--out', str(out), '--method', args.method,
                      '--quiet'] + extra)
            report = json.loads((out / 'report.json').read_text())
            solves = report['windows']
            median = sorted(w['seconds'] for w in solves)[len(solves) // 2]
            decoded = list(read_frames(folder))
            values = cli.resolve_parameters(cli.build_parser().parse_args(
                ['separate', str(folder), '--out', str(out), '--method', args.method] + extra))
            inline = detector_rate(decoded, values, threaded=False)
            threaded = detector_rate(decoded, values, threaded=True)
            print(f'{name}: {report["frames"]} frames, {report["fps"]:.1f} frames/s, '
                  f'{len(solves)} solves, median solve {median:.3f} s; detector alone on '
                  f'decoded frames: solves in line {inline:.1f} frames/s, in a worker '
                  f'{threaded:.1f} frames/s ({threaded / inline:.2f}x)', flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == '__main__':
    main()
