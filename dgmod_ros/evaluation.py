# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``dgmod evaluate``: the paper's comparison on CDnet-style sequences.

For each dataset and method: masks scored CDnet-style over the temporal ROI,
the mean background scored (RE, PSNR) against a reference, time and frames/s.
No dataset here has a ground-truth background image, so the reference is the
per-pixel temporal median of the grey frames over the pixels the ground truth
marks as background (0 or 50) inside the temporal ROI; a pixel that is never
background falls back to its median over all scored frames.
"""

from dataclasses import dataclass
import json
from pathlib import Path
import shutil
import time

import cv2
import numpy as np

from . import config
from .core.metrics import ConfusionCounts, GT_BACKGROUND, GT_SHADOW, psnr, relative_error
from .core.preprocess import to_float_channels, to_uint8
from .inputs import BadInput, read_frames
from .sequence import results


@dataclass
class Dataset:
    """A CDnet-style folder: frames, ground truth, scored frame range, ROI."""

    name: str
    path: Path
    truths: list
    first: int                  # 0-based index of the first scored frame
    last: int                   # 0-based index of the last scored frame
    roi: np.ndarray


def load_dataset(path):
    """Read a CDnet-style dataset's ground truth, temporal ROI and spatial ROI."""
    path = Path(path)
    truth_dir = path / 'groundtruth'
    if not (path / 'input').is_dir() or not truth_dir.is_dir():
        raise BadInput(f'{path} is not CDnet-style: it needs input/ and groundtruth/')
    truths = sorted(p for p in truth_dir.iterdir() if p.suffix.lower() in ('.png', '.bmp'))
    count = len(truths)
    first, last = 1, count
    roi_file = path / 'temporalROI.txt'
    if roi_file.is_file():
        first, last = (int(v) for v in roi_file.read_text().split()[:2])
    roi = cv2.imread(str(path / 'ROI.bmp'), cv2.IMREAD_GRAYSCALE) \
        if (path / 'ROI.bmp').is_file() else None
    return Dataset(path.name, path, truths, max(first, 1) - 1, min(last, count) - 1, roi)


def write_composite(source, out, transform, suffix=None):
    """
    Write a copy of the CDnet-style folder ``source`` whose inputs pass ``transform``.

    ``transform(index, image)`` takes each input frame in order (BGR uint8, as
    OpenCV reads it) and returns the frame to write; the ground truth,
    ``temporalROI.txt`` and ``ROI.bmp`` are copied as they are. ``suffix``
    (``'.png'``) names the written frames; None keeps each input's name.
    Return the number of frames written (the benchmarks' composites).
    """
    source, out = Path(source), Path(out)
    (out / 'input').mkdir(parents=True, exist_ok=True)
    shutil.copytree(source / 'groundtruth', out / 'groundtruth', dirs_exist_ok=True)
    for name in ('temporalROI.txt', 'ROI.bmp'):
        if (source / name).exists():
            shutil.copy(source / name, out / name)
    paths = sorted((source / 'input').iterdir())
    for index, path in enumerate(paths):
        name = path.name if suffix is None else path.stem + suffix
        cv2.imwrite(str(out / 'input' / name),
                    transform(index, cv2.imread(str(path), cv2.IMREAD_COLOR)))
    return len(paths)


def _grey(frame):
    """Return a frame's luma in [0, 1], the conversion every method's input goes through."""
    return to_float_channels(frame.image, frame.channel_order or 'rgb', 'gray')[:, :, 0]


def reference_background(frames, dataset):
    """Return the per-pixel median of the grey frames over ground-truth background."""
    stack, valid = [], []
    for index in range(dataset.first, dataset.last + 1):
        truth = cv2.imread(str(dataset.truths[index]), cv2.IMREAD_GRAYSCALE)
        stack.append(_grey(frames[index]))
        valid.append((truth == GT_BACKGROUND) | (truth == GT_SHADOW))
    stack = np.stack(stack)
    masked = np.where(np.stack(valid), stack, np.nan)
    reference = np.nanmedian(masked, axis=0) if np.any(valid) else np.median(stack, axis=0)
    never = np.isnan(reference)
    reference[never] = np.median(stack, axis=0)[never]
    return reference


def evaluate_method(frames, dataset, values, mode):
    """Run one method over one dataset; return its scores and example outputs."""
    counts = ConfusionCounts()
    background_sum, background_count = None, 0
    examples = {}
    # Before the clock, as in dgmod separate: a first run compiles them (a minute), and the
    # frames/s would count it.
    config.load_kernels(values)
    started = time.perf_counter()
    for frame, mask, background, _ in results(frames, values, mode):
        if background is not None:
            grey = to_float_channels(background, 'rgb', 'gray')[:, :, 0]
            background_sum = grey if background_sum is None else background_sum + grey
            background_count += 1
        if dataset.first <= frame.index <= dataset.last:
            truth = cv2.imread(str(dataset.truths[frame.index]), cv2.IMREAD_GRAYSCALE)
            counts.add(mask, truth, dataset.roi)
            if frame.index in (dataset.first, dataset.last):
                examples[frame.index] = mask
    seconds = time.perf_counter() - started
    return counts, (background_sum / max(background_count, 1)
                    if background_sum is not None else None), examples, seconds


def evaluate(paths, methods, values, mode, out, progress=None):
    """Evaluate every method on every dataset; write results and figures; return the rows."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for path in paths:
        dataset = load_dataset(path)
        frames = list(read_frames(dataset.path))
        bad = [f for f in frames if isinstance(f, BadInput)]
        if bad:
            raise bad[0]
        if len(frames) != len(dataset.truths):
            raise BadInput(f'{dataset.path}: {len(frames)} frames but '
                           f'{len(dataset.truths)} ground-truth masks')
        reference = reference_background(frames, dataset)
        backgrounds, examples = {}, {}
        for method in methods:
            method_values = dict(values, method=method)
            counts, background, shots, seconds = evaluate_method(frames, dataset,
                                                                 method_values, mode)
            row = {'dataset': dataset.name, 'method': method, 'mode': mode,
                   'precision': counts.precision, 'recall': counts.recall,
                   'fmeasure': counts.fmeasure, 're': None, 'psnr': None,
                   'seconds': seconds, 'fps': len(frames) / seconds, 'frames': len(frames),
                   'scored_frames': dataset.last - dataset.first + 1}
            if background is not None:
                row['re'] = relative_error(background, reference)
                row['psnr'] = psnr(np.clip(background, 0, 1), reference)
                backgrounds[method] = background
            examples[method] = shots
            rows.append(row)
            if progress is not None:
                progress(row)
        _write_figures(out, dataset, reference, backgrounds, examples)
    with open(out / 'results.json', 'w', encoding='utf-8') as handle:
        json.dump(rows, handle, indent=2)
    (out / 'results.md').write_text(results_table(rows))
    return rows


def results_table(rows):
    """Return the rows in the paper's Table I layout (one table per dataset), markdown."""
    lines = []
    for dataset in dict.fromkeys(r['dataset'] for r in rows):
        subset = [r for r in rows if r['dataset'] == dataset]
        lines += [f'### {dataset} ({subset[0]["frames"]} frames, {subset[0]["scored_frames"]} '
                  f'scored, mode {subset[0]["mode"]})', '',
                  '| method | RE | PSNR (dB) | Pr | Re | Fm | time (s) | frames/s |',
                  '| --- | --- | --- | --- | --- | --- | --- | --- |']
        best = max(r['fmeasure'] for r in subset)
        for r in subset:
            fm = f"**{r['fmeasure']:.4f}**" if r['fmeasure'] == best else f"{r['fmeasure']:.4f}"
            re = '-' if r['re'] is None else f"{r['re']:.4f}"
            ps = '-' if r['psnr'] is None else f"{r['psnr']:.2f}"
            lines.append(f"| {r['method']} | {re} | {ps} | {r['precision']:.4f} | "
                         f"{r['recall']:.4f} | {fm} | {r['seconds']:.1f} | {r['fps']:.1f} |")
        lines.append('')
    return '\n'.join(lines)


def _label(image, text):
    image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
    image = image.copy()
    cv2.putText(image, text, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 255), 1,
                cv2.LINE_AA)
    return image


def _write_figures(out, dataset, reference, backgrounds, examples):
    """Figure 1: mean background per method; figure 2: first and last scored masks."""
    tiles = [_label(to_uint8(reference), 'reference')]
    tiles += [_label(to_uint8(b), m) for m, b in backgrounds.items()]
    cv2.imwrite(str(out / f'figure1_backgrounds_{dataset.name}.png'), np.concatenate(tiles, 1))
    truth = [cv2.imread(str(dataset.truths[i]), cv2.IMREAD_GRAYSCALE)
             for i in (dataset.first, dataset.last)]
    columns = [np.concatenate([_label(t, f'truth {i + 1}') for t, i in
                               zip(truth, (dataset.first, dataset.last))], 0)]
    for method, shots in examples.items():
        column = [_label(shots.get(i, np.zeros_like(truth[0])), method)
                  for i in (dataset.first, dataset.last)]
        columns.append(np.concatenate(column, 0))
    cv2.imwrite(str(out / f'figure2_foregrounds_{dataset.name}.png'),
                np.concatenate(columns, 1))
