# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``dgmod``: the offline command (``separate`` and ``evaluate``).

``dgmod separate INPUT --out DIR`` runs one method over a folder of frames, a
video or a rosbag2 and writes ``DIR/masks/<stem>.png``,
``DIR/background/<stem>.png`` and ``DIR/report.json``. ``stream`` mode runs
the node's own streaming detector (same class, same parameters), ``batch``
mode tiles the sequence with windows. Outputs are written to ``DIR.partial``
and renamed to ``DIR`` only when complete, so a failed run never leaves an
output that looks finished.
"""

import argparse
from collections import deque
from concurrent.futures import ThreadPoolExecutor
import io
import json
from pathlib import Path
import queue
import shutil
import sys
import threading
import time

import cv2

from . import config
from .config import BATCH, OFFLINE, STREAM
from .core.preprocess import to_uint8
from .core.runtime import keep_freed_memory, yield_to_compute
from .evaluation import evaluate
from .inputs import BadInput, count_frames, input_kind, read_frames
from .sequence import results


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


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (the usage of ~60 options is not)."""

    def error(self, message):
        self.exit(2, f'{self.prog}: error: {message} (see {self.prog} --help)\n')


class _BooleanValue(argparse.Action):
    """``--x`` alone, or ``--x VALUE`` with true/false, yes/no, on/off, 1/0 (``--no-x``: false)."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            value = True if values is None else config.parse_bool(values)
        except ValueError as error:
            raise argparse.ArgumentError(self, str(error)) from None
        setattr(namespace, self.dest, value)


class _Removed(argparse.Action):
    """An option that was removed: refused with the name of the one that replaced it (const)."""

    def __call__(self, parser, namespace, values, option_string=None):
        raise argparse.ArgumentError(self, self.const)


#: Options that were removed, and what replaced them.
_REMOVED_OPTIONS = {'--threshold': 'removed (it was --mask-threshold again): use '
                                   '--mask-threshold'}

_MODE_TAGS = {(STREAM, BATCH): '', (STREAM,): ' [stream]', (BATCH,): ' [batch]'}

PARAMETER_HELP = ("parameters: the node's, defaults as in config/detector.yaml. [stream] or "
                  '[batch]: read in that --mode only. "Acts only with ...": no effect otherwise '
                  '(dgmod warns). Booleans: --x, --x true|false|yes|no|on|off|1|0, or --no-x.')


def option_name(name):
    """Return the command-line option of parameter ``name``."""
    return '--' + name.replace('_', '-')


def offline_parameters(command):
    """Return the table's parameters ``dgmod COMMAND`` offers as options."""
    # evaluate runs --methods; a --method beside it would do nothing.
    return [spec for spec in config.PARAMETERS if spec.where != 'node'
            and not (command == 'evaluate' and spec.name == 'method')]


def _add_parameter_options(parser, command):
    for title, specs in config.parameter_groups(offline_parameters(command)):
        group = parser.add_argument_group(title)
        for spec in specs:
            option = option_name(spec.name)
            tag = _MODE_TAGS[tuple(c for c in (STREAM, BATCH) if c in spec.acts)]
            text = config.describe(spec, OFFLINE) + tag
            kwargs = {'dest': spec.name, 'default': None, 'help': text.replace('%', '%%')}
            if isinstance(spec.default, bool):
                group.add_argument(option, action=_BooleanValue, nargs='?', metavar='BOOL',
                                   **kwargs)
                group.add_argument('--no-' + option[2:], dest=spec.name, action='store_const',
                                   const=False, help=argparse.SUPPRESS)
                continue
            if spec.choices:
                kwargs['choices'] = spec.choices
            else:
                kwargs['type'] = type(spec.default)
            group.add_argument(option, **kwargs)
    for option, message in _REMOVED_OPTIONS.items():
        parser.add_argument(option, action=_Removed, nargs='?', const=message,
                            help=argparse.SUPPRESS)


def build_parser():
    """Return the argument parser of ``dgmod``."""
    parser = _Parser(prog='dgmod', description=__doc__.strip().splitlines()[0])
    commands = parser.add_subparsers(dest='command', required=True)
    separate = commands.add_parser('separate', help='run one method over one input',
                                   description=PARAMETER_HELP)
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
    _add_parameter_options(separate, 'separate')
    evaluate = commands.add_parser('evaluate', help="the paper's comparison on CDnet-style "
                                   'datasets with ground truth', description=PARAMETER_HELP)
    evaluate.add_argument('datasets', nargs='+', help='CDnet-style folders (input/, '
                          'groundtruth/, temporalROI.txt)')
    evaluate.add_argument('--methods', default=','.join(config.BY_NAME['method'].choices),
                          help='comma-separated methods (default: all)')
    evaluate.add_argument('--mode', choices=('stream', 'batch'), default='stream',
                          help='stream: what the node does (causal); batch: whole windows')
    evaluate.add_argument('--out', required=True, help='folder for results and figures')
    evaluate.add_argument('--config', help="the node's YAML parameter file")
    _add_parameter_options(evaluate, 'evaluate')
    return parser


def resolve_parameters(args):
    """
    Return the full parameter set and where the user gave each parameter.

    Defaults, then ``--config``, then options. The second value maps each
    parameter given (an option, or a value of the file other than the
    default) to how to name it in a message.
    """
    values = dict(config.DEFAULTS)
    given = {}
    if args.config:
        from_file = config.load_parameter_file(args.config)
        values.update(from_file)
        given.update({name: f'{name} (in {args.config})' for name, value in from_file.items()
                      if value != config.DEFAULTS[name]})
    for spec in config.PARAMETERS:
        value = getattr(args, spec.name, None)
        if value is not None:
            values[spec.name] = value
            given[spec.name] = option_name(spec.name)
    for name, value in values.items():   # YAML ints for floats are fine offline
        if isinstance(config.DEFAULTS[name], float) and isinstance(value, int) \
                and not isinstance(value, bool):
            values[name] = float(value)
    return config.validate(values), given


def warn_inert(values, given, mode, methods=None):
    """
    Print one warning line for each parameter given that has no effect here.

    With ``methods`` (evaluate), only for those inert under every one of them.
    """
    inert = None
    for method in methods or (values['method'],):
        found = config.inert_parameters(dict(values, method=method), given, mode)
        inert = found if inert is None else {n: r for n, r in inert.items() if n in found}
    for name, reason in inert.items():
        print(f'dgmod: warning: {given[name]} has no effect: {reason}', file=sys.stderr)


def _good_frames(frames, skip_bad, skipped):
    """Yield frames of the first frame's size; stop on a bad one unless skipping."""
    size = None
    for frame in frames:
        if isinstance(frame, BadInput):
            if not skip_bad:
                raise frame
            skipped.append({'frame': None, 'reason': str(frame)})
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


# Frames read ahead and PNG files waiting to be written: a few frames of
# slack, so that decoding and encoding (OpenCV, without the GIL) overlap the
# separation without holding a sequence in memory.
_READ_AHEAD = 8
_WRITES_PENDING = 16


def read_ahead(iterable, depth=_READ_AHEAD):
    """
    Yield the items of ``iterable`` in order, produced ``depth`` ahead in a thread.

    An exception raised by ``iterable`` is raised here at its place in the
    order. Closing the generator stops the thread.
    """
    items = queue.Queue(maxsize=depth)
    stop = threading.Event()
    end = object()

    def produce():
        yield_to_compute()
        try:
            for item in iterable:
                while not stop.is_set():
                    try:
                        items.put((item, None), timeout=0.1)
                        break
                    except queue.Full:
                        continue
                if stop.is_set():
                    return
            items.put((end, None))
        except BaseException as error:  # noqa: B902 - handed to the consumer
            items.put((end, error))

    thread = threading.Thread(target=produce, name='dgmod-read', daemon=True)
    thread.start()
    try:
        while True:
            item, error = items.get()
            if error is not None:
                raise error
            if item is end:
                return
            yield item
    finally:
        stop.set()
        thread.join()


class PngWriter:
    """Write PNG files in a thread, at most ``_WRITES_PENDING`` waiting; errors raised here."""

    def __init__(self):
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix='dgmod-write',
                                        initializer=yield_to_compute)
        self._pending = deque()

    def write(self, path, image):
        """Queue one file (``image`` must not change afterwards)."""
        self._pending.append(self._pool.submit(_write_png, path, image))
        while len(self._pending) > _WRITES_PENDING:
            self._pending.popleft().result()

    def close(self):
        """Wait for every queued file; raise the first error."""
        try:
            while self._pending:
                self._pending.popleft().result()
        finally:
            self._pool.shutdown(wait=True, cancel_futures=True)


def _background_png(background):
    pixels = to_uint8(background)
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        return pixels[:, :, 0]
    return cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR) if pixels.ndim == 3 else pixels


def separate(args):
    """Run ``dgmod separate``; return the report dict."""
    input_kind(args.input)                      # a missing input: one line, before anything
    values, given = resolve_parameters(args)
    warn_inert(values, given, args.mode)
    out = Path(args.out)
    if out.exists() and not args.force:
        raise BadInput(f'{out} exists; choose another --out or pass --force')
    partial = out.with_name(out.name + '.partial')
    shutil.rmtree(partial, ignore_errors=True)
    (partial / 'masks').mkdir(parents=True)
    (partial / 'background').mkdir()
    skipped = []
    # Before the clock: the report's rate is the stream's, and start-up is
    # reported apart (docs/node.md).
    loading = time.perf_counter()
    config.load_kernels(values)
    started = time.perf_counter()
    progress = Progress(f'{values["method"]} {args.mode}', count_frames(args.input, args.topic),
                        stream=io.StringIO() if args.quiet else sys.stderr)
    windows = []
    writer = PngWriter()
    try:
        frames = read_ahead(_good_frames(read_frames(args.input, args.topic), args.skip_bad,
                                         skipped))
        try:
            for frame, mask, background, window in results(frames, values, args.mode):
                writer.write(partial / 'masks' / f'{frame.stem}.png', mask)
                if background is not None:
                    writer.write(partial / 'background' / f'{frame.stem}.png',
                                 _background_png(background))
                if window is not None:
                    windows.append(window)
                progress.step()
        finally:
            frames.close()
            writer.close()
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
              'kernel_load_seconds': started - loading,
              'windows': windows, 'skipped': skipped}
    with open(partial / 'report.json', 'w', encoding='utf-8') as handle:
        json.dump(report, handle, indent=2)
    if out.exists():
        shutil.rmtree(out)
    partial.rename(out)
    return report


def run_evaluation(args):
    """Run ``dgmod evaluate`` and print one line per (dataset, method)."""
    values, given = resolve_parameters(args)
    methods = [m.strip() for m in args.methods.split(',') if m.strip()]
    for method in methods:
        config.check_value('method', method)
    warn_inert(values, given, args.mode, methods)

    def show(row):
        print(f"{row['dataset']:>14} {row['method']:>7}: F {row['fmeasure']:.3f} (Pr "
              f"{row['precision']:.3f}, Re {row['recall']:.3f}), {row['fps']:.1f} frames/s",
              file=sys.stderr, flush=True)

    evaluate(args.datasets, methods, values, args.mode, args.out, show)
    print(f'results in {args.out}/results.md, results.json and figure*.png')


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
        else:
            run_evaluation(args)
    except (BadInput, ValueError, OSError) as error:
        print(f'dgmod: error: {error}', file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print('dgmod: interrupted; no output written', file=sys.stderr)
        return 130
    return 0


if __name__ == '__main__':
    sys.exit(main())
