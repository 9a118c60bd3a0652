# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Scripted people pasted on a clean background, with exact soft-edged ground truth.

An :class:`Actor` is a person (a track of cut-outs, or one cut-out) and its
script: per frame the feet's column and row, the person's height in pixels and
which of the track's cut-outs is drawn (its pose), or none. A
:class:`Scenario` draws its actors far to near over its background, each
through its feathered alpha, then applies the camera: a global gain (slight
light flicker) and per-pixel sensor noise (read noise plus shot noise), and
quantises to 8 bits. Its ground truth is the actors' combined alpha: 255
where it exceeds one half, 170 (unknown, not scored) where it is above one
grey level but at most one half, 0 elsewhere. Every frame is a pure function
of the scenario and the frame's number: the noise of frame ``k`` comes from
``numpy.random.default_rng((seed, code, k))``.
"""

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..inputs import Frame

FEATHER_SIGMA = 0.8         # pixels: the blur of a pasted person's outline
BAND_ALPHA = 1.0 / 255      # below this a person changes a pixel by less than a grey level
READ_NOISE = 1.5            # grey levels (of 255), each channel
SHOT_NOISE = 0.015          # variance per grey level of signal
FLICKER = 0.008             # peak relative change of the global light (0.8%)
FLICKER_JITTER = 0.002      # frame-to-frame relative jitter of the light


@dataclass
class Actor:
    """One person and its script (arrays of one entry per frame)."""

    cutouts: list               # material.Cutout, the poses
    source_height: float        # height of the person in the cut-outs, pixels
    x: np.ndarray               # feet column
    y: np.ndarray               # feet row
    height: np.ndarray          # person height drawn, pixels
    pose: np.ndarray            # index into cutouts, -1 = not drawn

    def sprite(self, k):
        """Return ``(rgb, alpha, top, left)`` of the person in frame ``k``, or None."""
        pose = int(self.pose[k])
        if pose < 0:
            return None
        cutout = self.cutouts[pose]
        scale = float(self.height[k]) / self.source_height
        rows, cols = cutout.mask.shape
        size = (max(int(round(cols * scale)), 1), max(int(round(rows * scale)), 1))
        interpolation = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
        rgb = cv2.resize(cutout.rgb, size, interpolation=interpolation)
        solid = (cv2.resize(cutout.mask, size, interpolation=cv2.INTER_LINEAR) > 0.5)
        alpha = cv2.GaussianBlur(solid.astype(np.float32), (0, 0), FEATHER_SIGMA)
        body = np.flatnonzero(solid.any(axis=1))
        columns = np.flatnonzero(solid.any(axis=0))
        if body.size == 0:
            return None
        feet_row = body[-1]
        centre = 0.5 * (columns[0] + columns[-1])
        top = int(round(self.y[k])) - int(feet_row)
        left = int(round(self.x[k] - centre))
        return rgb, alpha, top, left


@dataclass
class Scenario:
    """A scripted sequence: background, actors, camera; frames rendered on demand."""

    name: str
    description: str
    background: object          # material.Background
    actors: list
    frames_count: int
    fps: float
    seed: int
    code: int                   # distinguishes the scenarios' noise streams
    gain: np.ndarray            # global light gain per frame
    phases: dict = field(default_factory=dict)      # name -> (first, last) frame of a behaviour

    def __len__(self):
        return self.frames_count

    @property
    def shape(self):
        """Frame rows and columns."""
        return self.background.image.shape[:2]

    def coverage(self, k):
        """Return the actors' combined alpha in frame ``k`` (float32, frame size)."""
        return self._compose(k, with_image=False)[1]

    def render(self, k):
        """Return frame ``k`` as ``(rgb uint8 (H, W, 3), ground truth uint8 (H, W))``."""
        if not 0 <= k < self.frames_count:
            raise IndexError(f'frame {k} of a {self.frames_count}-frame scenario')
        image, cover = self._compose(k, with_image=True)
        rng = np.random.default_rng((self.seed, self.code, k))
        image *= self.gain[k]
        sigma = np.sqrt(READ_NOISE ** 2 + SHOT_NOISE * np.clip(image, 0, None))
        image += sigma * rng.standard_normal(image.shape, dtype=np.float32)
        rgb = np.clip(np.rint(image), 0, 255).astype(np.uint8)
        return rgb, truth_from_alpha(cover)

    def frames(self, count=None):
        """Yield the frames as :class:`dgmod_ros.inputs.Frame` objects (RGB)."""
        for k in range(self.frames_count if count is None else min(count, self.frames_count)):
            rgb, _ = self.render(k)
            yield Frame(k, f'in{k + 1:06d}', rgb, 'rgb')

    def _compose(self, k, with_image):
        rows, cols = self.shape
        image = self.background.image.copy() if with_image else None
        cover = np.zeros((rows, cols), np.float32)
        # far to near: a person whose feet are higher in the frame is behind
        for actor in sorted(self.actors, key=lambda a: a.y[k]):
            drawn = actor.sprite(k)
            if drawn is None:
                continue
            rgb, alpha, top, left = drawn
            y0, x0 = max(top, 0), max(left, 0)
            y1, x1 = min(top + alpha.shape[0], rows), min(left + alpha.shape[1], cols)
            if y1 <= y0 or x1 <= x0:
                continue
            a = alpha[y0 - top:y1 - top, x0 - left:x1 - left]
            if with_image:
                patch = rgb[y0 - top:y1 - top, x0 - left:x1 - left]
                region = image[y0:y1, x0:x1]
                region += a[..., None] * (patch - region)
            cover[y0:y1, x0:x1] += a * (1.0 - cover[y0:y1, x0:x1])
        return image, cover


def truth_from_alpha(alpha):
    """Ground truth of a combined alpha: 255 above 0.5, 170 in the soft band, 0 elsewhere."""
    truth = np.zeros(alpha.shape, np.uint8)
    truth[alpha > BAND_ALPHA] = 170
    truth[alpha > 0.5] = 255
    return truth


def flicker(count, fps, rng):
    """Global light gain per frame: a slow beat of mains lighting plus a small jitter."""
    t = np.arange(count) / fps
    beat = rng.uniform(0.3, 1.2)
    gain = 1.0 + FLICKER * np.sin(2 * np.pi * beat * t + rng.uniform(0, 2 * np.pi))
    return (gain + FLICKER_JITTER * rng.standard_normal(count)).astype(np.float32)


def wander(count, fps, rng, low_hz=0.05, high_hz=0.35):
    """Return a smooth bounded path in [-1, 1]: three sinusoids of random slow frequencies."""
    t = np.arange(count) / fps
    path = sum(np.sin(2 * np.pi * rng.uniform(low_hz, high_hz) * t + rng.uniform(0, 2 * np.pi))
               for _ in range(3))
    return path / 3.0


class Script:
    """
    Build an actor's per-frame arrays segment by segment.

    ``walk`` moves the feet at a constant speed with the track animating,
    ``linger`` moves them along a small smooth path about where they are (the
    track animating), ``still`` holds position and pose exactly, ``away``
    leaves the person undrawn.
    """

    def __init__(self, x, y, fps, track_length, rng):
        self.x, self.y, self.fps, self.rng = float(x), float(y), fps, rng
        self.track_length = track_length
        self.pose_step = 0
        self.columns = {'x': [], 'y': [], 'pose': []}

    def _pose(self):
        # ping-pong through the track, one cut-out per frame
        period = max(2 * (self.track_length - 1), 1)
        phase = self.pose_step % period
        return phase if phase < self.track_length else period - phase

    def _emit(self, x, y, pose):
        self.columns['x'].append(x)
        self.columns['y'].append(y)
        self.columns['pose'].append(pose)

    def walk(self, to_x, speed):
        """Walk to column ``to_x`` at ``speed`` pixels per frame."""
        steps = max(int(np.ceil(abs(to_x - self.x) / speed)), 1)
        for x in np.linspace(self.x, to_x, steps + 1)[1:]:
            self.pose_step += 1
            self._emit(x, self.y, self._pose())
        self.x = float(to_x)

    def linger(self, frames, amplitude_x, amplitude_y):
        """Move about within ``amplitude`` pixels of here for ``frames`` frames."""
        dx = wander(frames, self.fps, self.rng)
        dy = wander(frames, self.fps, self.rng)
        dx, dy = dx - dx[0], dy - dy[0]
        for k in range(frames):
            self.pose_step += 1
            self._emit(self.x + amplitude_x * dx[k], self.y + amplitude_y * dy[k], self._pose())
        self.x, self.y = self.x + amplitude_x * dx[-1], self.y + amplitude_y * dy[-1]

    def still(self, frames, pose=None):
        """Hold position and pose (by default the last) exactly for ``frames`` frames."""
        pose = self._pose() if pose is None else int(pose)
        for _ in range(frames):
            self._emit(self.x, self.y, pose)

    def away(self, frames):
        """Not in view for ``frames`` frames."""
        for _ in range(frames):
            self._emit(self.x, self.y, -1)

    def __len__(self):
        return len(self.columns['x'])

    def actor(self, cutouts, source_height, height_of_row, count):
        """Return the :class:`Actor`, padded with ``away`` frames to ``count`` frames."""
        if len(self) < count:
            self.away(count - len(self))
        x = np.asarray(self.columns['x'][:count], np.float32)
        y = np.asarray(self.columns['y'][:count], np.float32)
        pose = np.asarray(self.columns['pose'][:count], np.int32)
        height = np.asarray([height_of_row(v) for v in y], np.float32)
        return Actor(cutouts, source_height, x, y, height, pose)
