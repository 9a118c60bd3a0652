# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The real material of the scenario suite: clean backgrounds and cut-out people.

Both come from a CDnet-style folder's frames and ground truth (255 foreground,
170 unknown band, 0 and 50 background) and nothing else:

* a clip's **clean background** is, at each pixel, the median of the frames in
  which the ground truth calls that pixel background (away from the foreground
  and its unknown band by a margin); pixels never seen as background in enough
  frames are marked and filled by inpainting from their neighbours, and a clip
  with too many of them is not used as a background;
* a **person** is a connected component of the ground truth's 255 pixels that
  is alone in its frame (no other sizeable blob, nothing else inside its box),
  upright and away from the frame's left, top and right edges (whole); runs of
  consecutive frames of such blobs are **tracks**, whose frames animate a
  pasted person (legs and arms move as they did).

A clip's ground-truth blobs also give its scene's perspective: person height
against the row of the feet, fitted over its clean blobs, so people pasted on
its background get plausible sizes for where they stand.
"""

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

GT_FOREGROUND = 255
GT_UNKNOWN = 170
GT_BACKGROUND_VALUES = (0, 50)
IMAGE_SUFFIXES = ('.png', '.jpg', '.jpeg', '.bmp')

# Clips of the shared data with people in them (the sources of cut-outs and of
# backgrounds); the highway has cars only.
PEOPLE_CLIPS = ('sbi_IBMtest2', 'sbi_CAVIAR1', 'sbi_CAVIAR2', 'sbi_Candela_m1.10',
                'sbi_HumanBody2', 'sbi_CaVignal')


@dataclass
class Cutout:
    """One person cut out of one frame: colour, binary mask, where it came from."""

    rgb: np.ndarray             # (h, w, 3) float32 in [0, 255], the blob's box plus a margin
    mask: np.ndarray            # (h, w) float32, 1 on the ground truth's 255 pixels
    clip: str
    frame: int
    bottom_cropped: bool        # the blob touches the frame's bottom edge

    @property
    def height(self):
        """Rows the person's mask spans."""
        rows = np.flatnonzero(self.mask.any(axis=1))
        return int(rows[-1] - rows[0] + 1)

    @property
    def area(self):
        """Pixels of the person's mask."""
        return float(self.mask.sum())


@dataclass
class Track:
    """Cut-outs of one person in consecutive frames of one clip."""

    clip: str
    cutouts: list

    def __len__(self):
        return len(self.cutouts)

    @property
    def height(self):
        """Median height of the person over the track (pixels of the source)."""
        return float(np.median([c.height for c in self.cutouts]))


@dataclass
class Background:
    """A clip's clean background and the pixels that had to be filled."""

    clip: str
    image: np.ndarray           # (H, W, 3) float32 RGB in [0, 255]
    unseen: np.ndarray          # (H, W) bool: never seen as background, filled by inpainting
    perspective: tuple = None   # (slope, intercept, lowest feet row, highest feet row) or None

    @property
    def unseen_fraction(self):
        """Share of the pixels that were filled."""
        return float(self.unseen.mean())

    def person_height(self, feet_row):
        """Person height in pixels for feet at ``feet_row``, from the clip's own people."""
        slope, intercept, _, _ = self.perspective
        return float(slope * feet_row + intercept)


@dataclass
class Material:
    """Everything the suite is built from: backgrounds and people tracks."""

    backgrounds: dict = field(default_factory=dict)     # clip -> Background
    tracks: list = field(default_factory=list)          # Track, whole people
    close_ups: list = field(default_factory=list)       # Track, people cut by the frame's bottom


def _numbered(folder):
    files = sorted(p for p in Path(folder).iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise FileNotFoundError(f'no images in {folder}')
    return files


def _read_rgb(path):
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if image is None:
        raise OSError(f'cannot decode {path}')
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def clean_background(clip_dir, max_frames=150, margin=2, min_seen=3):
    """
    Return a clip's :class:`Background`: the median of its ground-truth background.

    Parameters
    ----------
    clip_dir : path
        CDnet-style folder (``input/``, ``groundtruth/``).
    max_frames : int
        Frames the median is taken over, evenly spaced over the clip (the
        median of 150 frames is as good as that of all of them, at a tenth of
        the memory).
    margin : int
        Pixels next to the foreground or the unknown band that do not count as
        background (a blob's outline in the ground truth is a pixel or two off).
    min_seen : int
        Frames a pixel must be background in; fewer and it is marked unseen
        and filled from its neighbours (``cv2.inpaint``).

    """
    clip_dir = Path(clip_dir)
    inputs, truths = _numbered(clip_dir / 'input'), _numbered(clip_dir / 'groundtruth')
    picks = np.unique(np.linspace(0, len(inputs) - 1, min(max_frames, len(inputs))).astype(int))
    kernel = np.ones((2 * margin + 1, 2 * margin + 1), np.uint8)
    frames, valid = [], []
    for index in picks:
        truth = cv2.imread(str(truths[index]), cv2.IMREAD_GRAYSCALE)
        background = np.isin(truth, GT_BACKGROUND_VALUES)
        valid.append(cv2.erode(background.astype(np.uint8), kernel) > 0)
        frames.append(_read_rgb(inputs[index]))
    valid = np.stack(valid)
    frames = np.stack(frames)
    seen = valid.sum(axis=0)
    image = np.empty(frames.shape[1:], np.float32)
    # The median of each pixel's valid values: a sort puts NaN last, so the
    # middle of the first ``seen`` entries is the median of the valid ones.
    middle = (np.maximum(seen, 1) - 1)[None] // 2
    for channel in range(3):
        values = np.sort(np.where(valid, frames[..., channel].astype(np.float32), np.nan), axis=0)
        image[..., channel] = np.nan_to_num(np.take_along_axis(values, middle, axis=0)[0])
    unseen = seen < min_seen
    if unseen.any():
        filled = cv2.inpaint(np.clip(image, 0, 255).astype(np.uint8),
                             unseen.astype(np.uint8), 5, cv2.INPAINT_TELEA)
        image[unseen] = filled[unseen]
    return Background(clip_dir.name, image, unseen)


def _clean_blobs(truth, min_area):
    """Yield ``(label mask, x, y, w, h, area)`` of the frame's blob when it is alone."""
    foreground = (truth == GT_FOREGROUND).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(foreground, connectivity=8)
    big = [i for i in range(1, count) if stats[i, cv2.CC_STAT_AREA] >= min_area]
    if len(big) != 1:
        return None
    i = big[0]
    x, y, w, h, area = (int(v) for v in stats[i])
    box = (slice(max(y - 3, 0), y + h + 3), slice(max(x - 3, 0), x + w + 3))
    others = (foreground[box] > 0) & (labels[box] != i)
    if others.sum() > 0.01 * area:
        return None
    return labels == i, x, y, w, h, area


def people(clip_dir, min_area=300, pad=4, min_aspect=1.8):
    """
    Return the clean person blobs of a clip as lists of whole and cropped cut-outs.

    A blob is kept when it is its frame's only sizeable one, upright (height
    at least ``min_aspect`` times its width) and inside the frame's left, top
    and right edges; one touching the bottom edge is kept apart as a cropped
    cut-out (a close-up's body continues below the frame). Returns
    ``(whole, cropped, feet)``: lists of :class:`Cutout` and the
    ``(feet row, height)`` pairs of the whole ones.
    """
    clip_dir = Path(clip_dir)
    inputs, truths = _numbered(clip_dir / 'input'), _numbered(clip_dir / 'groundtruth')
    whole, cropped, feet = [], [], []
    for index, (image_path, truth_path) in enumerate(zip(inputs, truths)):
        truth = cv2.imread(str(truth_path), cv2.IMREAD_GRAYSCALE)
        blob = _clean_blobs(truth, min_area)
        if blob is None:
            continue
        mask, x, y, w, h, _ = blob
        rows, cols = truth.shape
        if x == 0 or y == 0 or x + w == cols or h < min_aspect * w:
            continue
        bottom = y + h == rows
        y0, y1 = max(y - pad, 0), min(y + h + pad, rows)
        x0, x1 = max(x - pad, 0), min(x + w + pad, cols)
        rgb = _read_rgb(image_path)[y0:y1, x0:x1].astype(np.float32)
        cutout = Cutout(rgb, mask[y0:y1, x0:x1].astype(np.float32), clip_dir.name, index, bottom)
        if bottom:
            cropped.append(cutout)
        else:
            whole.append(cutout)
            feet.append((y + h - 1, h))
    return whole, cropped, feet


def tracks_of(cutouts, min_length=8):
    """Split a clip's whole cut-outs into runs of consecutive frames (:class:`Track`)."""
    tracks, run = [], []
    for cutout in cutouts:
        if run and (cutout.frame != run[-1].frame + 1 or cutout.clip != run[-1].clip):
            if len(run) >= min_length:
                tracks.append(Track(run[0].clip, run))
            run = []
        run.append(cutout)
    if len(run) >= min_length:
        tracks.append(Track(run[0].clip, run))
    return tracks


def fit_perspective(feet, rows, min_blobs=20):
    """
    Fit person height against feet row over a clip's clean blobs.

    Returns ``(slope, intercept, lowest row, highest row)`` (the rows between
    the 10th and 90th percentile of the feet seen) or None with fewer than
    ``min_blobs`` blobs or a fit that does not grow towards the camera.
    """
    if len(feet) < min_blobs:
        return None
    feet = np.asarray(feet, np.float64)
    slope, intercept = np.polyfit(feet[:, 0], feet[:, 1], 1)
    low, high = np.percentile(feet[:, 0], [10, 90])
    if slope < 0 or slope * high + intercept > 0.95 * rows:
        slope, intercept = 0.0, float(np.median(feet[:, 1]))
    return float(slope), float(intercept), float(low), float(high)


def load_material(data_dir, clips=PEOPLE_CLIPS, max_unseen=0.02):
    """
    Read every clip's background and people from ``data_dir``.

    A clip whose background has more than ``max_unseen`` of its pixels never
    seen as background is not used as a background (its people still are).
    """
    data_dir = Path(data_dir)
    material = Material()
    for clip in clips:
        path = data_dir / clip
        if not (path / 'input').is_dir():
            continue
        whole, cropped, feet = people(path)
        material.tracks += tracks_of(whole)
        material.close_ups += tracks_of(cropped)
        background = clean_background(path)
        background.perspective = fit_perspective(feet, background.image.shape[0])
        if background.unseen_fraction <= max_unseen:
            material.backgrounds[clip] = background
    if not material.backgrounds or not material.tracks:
        raise FileNotFoundError(f'no usable backgrounds or people under {data_dir}')
    return material
