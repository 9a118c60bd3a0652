# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``dgmod``: the offline command.

``dgmod separate INPUT --out DIR`` runs one method over a folder of frames, a
video or a rosbag2 and writes ``DIR/masks/<stem>.png``,
``DIR/background/<stem>.png`` and ``DIR/report.json``. ``stream`` mode runs
the node's own streaming detector (same class, same parameters), ``batch``
mode tiles the sequence with windows. Outputs are written to ``DIR.partial``
and renamed to ``DIR`` only when complete, so a failed run never leaves an
output that looks finished.
"""

import argparse
import io
import json
from pathlib import Path
import shutil
import sys
import time

import cv2
import numpy as np

from . import config
from .core.pipeline import batch_separate
from .core.runtime import keep_freed_memory
from .inputs import BadInput, count_frames, read_frames


class Progress:
    """A one-line progress bar on stderr, redrawn at most every 0.2 s."""

    def __init__(self, label, total=None, stream=sys.stderr):
        self.label = label
        self.total = total
        self.stream = stream
        self.count = 0
        self._last = 0.0
        self._started = time.monotonic()

    def step(self, count=1):
        self.count += count
        now = time.monotonic()
        if now - self._last >= 0.2:
            self._last = now
            self._draw(now)

    def _draw(self, now):
        rate = self.count / max(now - self._started, 1e-9)
        if self.total:
            done = min(1.0, self.count / self.total)
            bar = f'[{"#" * int(30 * done):<30}] {self.count}/{self.total}'
        else:
            bar = f'{self.count} frames'
        self.stream.write(f'\r{self.label} {bar}, {rate:.1f} frames/s')
        self.stream.flush()

    def close(self):
        self._draw(time.monotonic())
        self.stream.write('\n')
        self.stream.flush()


def _add_parameter_options(parser):
    group = parser.add_argument_group('model, window and mask parameters (defaults: the '
                                      "node's; see config/detector.yaml)")
    for spec in config.PARAMETERS:
        if spec.name in ('solve_mode', 'publish_overlay', 'diagnostics_period', 'max_pixels'):
            continue
        kind = type(spec.default)
        option = '--' + spec.name.replace('_', '-')
        kwargs = {'dest': spec.name, 'default': None, 'help': spec.description}
        if spec.choices:
            kwargs['choices'] = spec.choices
        else:
            kwargs['type'] = kind
        group.add_argument(option, **kwargs)
    parser.add_argument('--threshold', type=float, default=None,
                        help='fixed mask threshold for every method (= --mask-threshold)')


def build_parser():
    """Return the argument parser of ``dgmod``."""
    parser = argparse.ArgumentParser(prog='dgmod', description=__doc__.strip().splitlines()[0])
    commands = parser.add_subparsers(dest='command', required=True)
    separate = commands.add_parser('separate', help='run one method over one input')
    separate.add_argument('input', help='folder of frames (plain or CDnet-style), video file, '
                          'or rosbag2 (folder, .mcap, .db3)')
    separate.add_argument('--out', required=True, help='output folder')
    separate.add_argument('--mode', choices=('stream', 'batch'), default='stream',
                          help='stream: what the node does (causal); batch: whole windows')
    separate.add_argument('--config', help="the node's YAML parameter file")
    separate.add_argument('--topic', help='image topic of a rosbag2 input')
    separate.add_argument('--skip-bad', action='store_true',
                          help='skip unreadable frames and frames of another size, and report '
                               'them, instead of stopping')
    separate.add_argument('--force', action='store_true', help='replace an existing --out')
    separate.add_argument('--quiet', action='store_true', help='no progress bar')
    _add_parameter_options(separate)
    return parser


def resolve_parameters(args):
    """Return the full parameter set: defaults, then ``--config``, then options."""
    values = dict(config.DEFAULTS)
    if args.config:
        values.update(config.load_parameter_file(args.config))
    for spec in config.PARAMETERS:
        given = getattr(args, spec.name, None)
        if given is not None:
            values[spec.name] = given
    if args.threshold is not None:
        values['mask_threshold'] = args.threshold
    for name, value in values.items():   # YAML ints for floats are fine offline
        if isinstance(config.DEFAULTS[name], float) and isinstance(value, int):
            values[name] = float(value)
    return config.validate(values)


def _good_frames(frames, skip_bad, skipped):
    """Yield frames of the first frame's size; stop on a bad one unless skipping."""
    size = None
    iterator = iter(frames)
    while True:
        try:
            frame = next(iterator)
        except StopIteration:
            return
        except BadInput as error:
            if not skip_bad:
                raise
            skipped.append({'frame': None, 'reason': str(error)})
            if 'cannot open' in str(error) or 'no readable' in str(error):
                return
            continue
        if size is None:
            size = frame.image.shape[:2]
        if frame.image.shape[:2] != size:
            message = (f'frame {frame.stem} is {frame.image.shape[1]} x {frame.image.shape[0]}, '
                       f'the sequence started at {size[1]} x {size[0]}')
            if not skip_bad:
                raise BadInput(message + ' (use --skip-bad to skip such frames)')
            skipped.append({'frame': frame.stem, 'reason': message})
            continue
        yield frame


def _write_png(path, image):
    if not cv2.imwrite(str(path), image):
        raise OSError(f'cannot write {path}')


def _background_png(background):
    pixels = np.clip(np.asarray(background) * 255.0 + 0.5, 0, 255).astype(np.uint8)
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        return pixels[:, :, 0]
    return cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR) if pixels.ndim == 3 else pixels


def run_stream(frames, values, out, progress):
    """Run the node's streaming detector over the frames; return the solve records."""
    detector = config.build_detector(values)
    windows = []
    value_range = values['value_range'] or None
    for frame in frames:
        result, solved = detector.process(frame.image, frame.channel_order, value_range)
        _write_png(out / 'masks' / f'{frame.stem}.png', result.mask)
        if solved is not None:
            windows.append({'first_frame': solved.first_id, 'last_frame': solved.last_id,
                            'seconds': solved.seconds, 'iterations': solved.iterations,
                            'info': solved.info})
            background = cv2.resize(solved.background, frame.image.shape[1::-1])
            _write_png(out / 'background' / f'{frame.stem}.png', _background_png(background))
        elif values['method'] in config.ONLINE_METHODS and \
                result.frame_id % values['stride'] == values['stride'] - 1:
            background = cv2.resize(detector.background_image(), frame.image.shape[1::-1])
            _write_png(out / 'background' / f'{frame.stem}.png', _background_png(background))
        progress.step()
    return windows


def run_batch(frames, values, out, progress):
    """Tile the sequence with windows; return the solve records."""
    frames = list(frames)
    if not frames:
        return []
    order = frames[0].channel_order
    model = config.window_model(values)
    windows = []
    separated = batch_separate([f.image for f in frames], model, window=values['window'],
                               scale=values['scale'], color=values['color'],
                               mask_rule=config.build_mask_rule(values), channel_order=order,
                               value_range=values['value_range'] or None)
    for index, mask, background, record in separated:
        stem = frames[index].stem
        _write_png(out / 'masks' / f'{stem}.png', mask)
        if record is not None:
            windows.append({'first_frame': record.first, 'last_frame': record.last,
                            'seconds': record.seconds, 'iterations': record.iterations})
            full = cv2.resize(background, frames[index].image.shape[1::-1])
            _write_png(out / 'background' / f'{stem}.png', _background_png(full))
        progress.step()
    return windows


def separate(args):
    """Run ``dgmod separate``; return the report dict."""
    values = resolve_parameters(args)
    out = Path(args.out)
    if out.exists() and not args.force:
        raise BadInput(f'{out} exists; choose another --out or pass --force')
    partial = out.with_name(out.name + '.partial')
    shutil.rmtree(partial, ignore_errors=True)
    (partial / 'masks').mkdir(parents=True)
    (partial / 'background').mkdir()
    skipped = []
    progress = Progress(f'{values["method"]} {args.mode}', count_frames(args.input, args.topic),
                        stream=io.StringIO() if args.quiet else sys.stderr)
    started = time.perf_counter()
    try:
        frames = _good_frames(read_frames(args.input, args.topic), args.skip_bad, skipped)
        runner = run_stream if args.mode == 'stream' else run_batch
        windows = runner(frames, values, partial, progress)
    except BaseException:
        shutil.rmtree(partial, ignore_errors=True)
        raise
    finally:
        progress.close()
    seconds = time.perf_counter() - started
    count = progress.count
    if count == 0:
        shutil.rmtree(partial, ignore_errors=True)
        raise BadInput(f'no frame of {args.input} could be used')
    report = {'method': values['method'], 'mode': args.mode, 'input': str(args.input),
              'parameters': values, 'frames': count, 'seconds': seconds,
              'fps': count / seconds if seconds > 0 else float('inf'),
              'windows': windows, 'skipped': skipped}
    with open(partial / 'report.json', 'w', encoding='utf-8') as handle:
        json.dump(report, handle, indent=2)
    if out.exists():
        shutil.rmtree(out)
    partial.rename(out)
    return report


def main(argv=None):
    """Entry point of ``dgmod``; returns the exit status."""
    keep_freed_memory()
    args = build_parser().parse_args(argv)
    try:
        if args.command == 'separate':
            report = separate(args)
            print(f"{report['frames']} frames in {report['seconds']:.1f} s "
                  f"({report['fps']:.1f} frames/s), {len(report['windows'])} window solves, "
                  f"{len(report['skipped'])} skipped; outputs in {args.out}")
    except (BadInput, ValueError, OSError) as error:
        print(f'dgmod: error: {error}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('dgmod: interrupted; no output written', file=sys.stderr)
        return 130
    return 0


if __name__ == '__main__':
    sys.exit(main())
