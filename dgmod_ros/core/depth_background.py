# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The static scene's depth per pixel, and each pixel's verdict against it (no ROS import).

Depth is a witness that does not care about colour, light or how long a person
stands still: whatever is nearer than the static scene by more than the
sensor's noise is in front of it. :class:`DepthBackground` learns that scene
from the stream and says, for every pixel of a new depth image, whether it is
nearer (foreground), at the scene's depth or behind it (background), or
unknown (no reading, or a pixel not yet learnt). :func:`fuse_masks` combines
the verdict with a colour mask: depth decides where it knows, colour where it
does not.

The model keeps, per pixel, the far side of what it sees: people pass in
front of the wall, never behind it, so a reading nearer than the model is
evidence of something in front (held out of the model until ``absorb_frames``
such readings), and a reading behind it that repeats (``reveal_frames``
consistent readings) is the scene uncovered (the model jumps back to it).
Readings at the model's depth refine it by a running mean over up to
``span_frames`` readings. Noise is the structured-light / stereo model
``sigma(z) = noise_base + noise_quadratic * z**2`` (disparity noise of a
fixed number of subpixels makes depth noise grow with z squared).
"""

import numpy as np

from .kernels import depth_background as depth_kernel

#: Verdicts of :meth:`DepthBackground.update`, one uint8 per pixel.
UNKNOWN, BACKGROUND, FOREGROUND = np.uint8(0), np.uint8(1), np.uint8(2)
# A scene change is judged only on a frame with this share of trusted readings.
_FEWEST_JUDGED = 0.05


def depth_noise(depth_m, noise_base, noise_quadratic):
    """Return the sensor's depth noise (standard deviation, metres) at ``depth_m``."""
    depth_m = np.asarray(depth_m, dtype=np.float32)
    return np.float32(noise_base) + np.float32(noise_quadratic) * depth_m * depth_m


class DepthBackground:
    """
    Per-pixel depth of the static scene, learnt from a depth stream.

    Parameters
    ----------
    noise_base : float, default=0.002
        Depth noise (m) at zero distance: the floor of the noise model (1 mm
        quantisation of 16UC1 images and the sensor's own floor).
    noise_quadratic : float, default=0.005
        Growth of the noise with distance squared (1/m). A RealSense D435 at
        640 x 480 (focal length about 380 px, baseline 50 mm, subpixel 0.08)
        has 0.08 / (380 * 0.05) = 0.004; 0.005 leaves room for a worse surface.
    noise_k : float, default=4.0
        A pixel nearer than the model by more than ``noise_k`` noise levels
        is foreground; within that, at the scene's depth.
    absorb_frames : int, default=5400
        Readings nearer than the model that a pixel needs before what stands
        there joins the static scene (a parked object): until then a person
        who stands still stays foreground. The node passes its own
        ``absorb_frames``.
    learn_frames : int, default=10
        Readings at the model's depth before a pixel is trusted; until then
        its verdict is unknown.
    reveal_frames : int, default=5
        Consistent readings behind the model that move it back (what stood
        there at start-up, or a parked object that has left).
    span_frames : int, default=300
        Readings the running mean of a pixel's depth spans at most.
    change_fraction : float, default=0.25
        Share of the trusted pixels with a reading that, behind the model in
        one frame, restarts it (the camera moved: a person can hide the scene
        but never put it farther away); 1.0 disables.
    compiled : bool, default=True
        Run the update as two compiled passes (:mod:`dgmod_ros.core.kernels.depth_background`);
        False runs their numpy references there (the same results, bit for bit).

    Attributes
    ----------
    background_ : ndarray (h, w) float32
        The static scene's depth in metres, NaN where never seen.
    hits_ : ndarray (h, w) float32
        Readings at the model's depth so far (capped at ``span_frames``).
    near_frames_ : ndarray (h, w) int32
        Readings nearer than the model since the pixel last matched it.
    frames_, scene_changes_ : int
        Depth images seen since the last restart; restarts on a scene change.

    References
    ----------
    .. [1] Keselman et al., "Intel RealSense Stereoscopic Depth Cameras",
       CVPR Workshops 2017 (RMS depth error grows with z**2 / (focal * baseline)).
    .. [2] Harville, Gordon, Woodfill, "Foreground segmentation using adaptive
       mixture models in color and depth", IEEE Workshop on Detection and
       Recognition of Events in Video, 2001 (depth as a background cue).

    """

    def __init__(self, noise_base=0.002, noise_quadratic=0.005, noise_k=4.0,
                 absorb_frames=5400, learn_frames=10, reveal_frames=5, span_frames=300,
                 change_fraction=0.25, compiled=True):
        self.noise_base = noise_base
        self.noise_quadratic = noise_quadratic
        self.noise_k = noise_k
        self.absorb_frames = absorb_frames
        self.learn_frames = learn_frames
        self.reveal_frames = reveal_frames
        self.span_frames = span_frames
        self.change_fraction = change_fraction
        self.compiled = compiled
        self.scene_changes_ = 0
        self.reset()

    def validate(self):
        """Check the parameters; return self."""
        for name in ('noise_base', 'noise_quadratic'):
            if not getattr(self, name) >= 0:
                raise ValueError(f'{name} must be >= 0, got {getattr(self, name)!r}')
        if not self.noise_base + self.noise_quadratic > 0:
            raise ValueError('the noise model must not be zero everywhere')
        if not self.noise_k > 0:
            raise ValueError(f'noise_k must be > 0, got {self.noise_k!r}')
        for name in ('absorb_frames', 'learn_frames', 'reveal_frames', 'span_frames'):
            value = getattr(self, name)
            if int(value) != value or value < 1:
                raise ValueError(f'{name} must be an integer >= 1, got {value!r}')
        if not 0 < self.change_fraction <= 1:
            raise ValueError(f'change_fraction must be in (0, 1], got {self.change_fraction!r}')
        return self

    def reset(self):
        """Forget the scene (the camera moved, ``~/reset_background``)."""
        self.background_ = None
        self.hits_ = None
        self.near_frames_ = None
        self._far_depth = None
        self._far_frames = None
        self.frames_ = 0

    @property
    def ready_(self):
        """Whether any pixel is trusted yet."""
        return self.hits_ is not None and bool(np.any(self.hits_ >= self.learn_frames))

    def noise(self):
        """Return the noise level (m) at the model's depth, NaN where it knows none."""
        return depth_noise(self.background_, self.noise_base, self.noise_quadratic)

    def _start(self, shape):
        self.background_ = np.full(shape, np.nan, np.float32)
        self.hits_ = np.zeros(shape, np.float32)
        self.near_frames_ = np.zeros(shape, np.int32)
        self._far_depth = np.full(shape, np.nan, np.float32)
        self._far_frames = np.zeros(shape, np.int32)
        self.frames_ = 0

    def update(self, depth_m):
        """
        Judge a depth image against the model, then learn from it.

        Parameters
        ----------
        depth_m : ndarray (h, w) float32
            Metres, NaN where there is no reading
            (:func:`dgmod_ros.core.depth.depth_in_metres`). A new size
            restarts the model.

        Returns
        -------
        verdict : ndarray (h, w) uint8
            :data:`FOREGROUND` where the reading is nearer than the trusted
            model by more than ``noise_k`` noise levels, :data:`BACKGROUND`
            where it is at or behind the model's depth, :data:`UNKNOWN`
            where there is no reading or the pixel is not trusted yet (and
            everywhere in a frame that restarted the model).

        """
        depth = np.asarray(depth_m, dtype=np.float32)
        if depth.ndim != 2:
            raise ValueError(f'expected an (h, w) depth image, got shape {depth.shape}')
        if self.background_ is None or self.background_.shape != depth.shape:
            self._start(depth.shape)
        depth = np.require(depth, np.float32, 'CW')     # the compiled passes' one layout
        verdict, judged, behind = self._judge(depth)
        if self.change_fraction < 1 and judged >= _FEWEST_JUDGED * depth.size \
                and behind > self.change_fraction * judged:
            self.scene_changes_ += 1
            self._start(depth.shape)          # and learnt from this image on
            verdict[:] = UNKNOWN
        self.frames_ += 1
        self._learn(depth)
        return verdict

    def _scalars(self):
        return (np.float32(self.noise_k), np.float32(self.noise_base),
                np.float32(self.noise_quadratic))

    def _judge(self, depth):
        judge = depth_kernel.judge if self.compiled else depth_kernel.judge_reference
        verdict = np.empty(depth.shape, np.uint8)
        judged, behind = judge(
            depth.reshape(-1), self.background_.reshape(-1), self.hits_.reshape(-1),
            *self._scalars(), np.float32(self.learn_frames), verdict.reshape(-1))
        return verdict, judged, behind

    def _learn(self, depth):
        learn = depth_kernel.learn if self.compiled else depth_kernel.learn_reference
        learn(depth.reshape(-1), self.background_.reshape(-1), self.hits_.reshape(-1),
              self.near_frames_.reshape(-1), self._far_depth.reshape(-1),
              self._far_frames.reshape(-1), *self._scalars(), np.float32(self.span_frames),
              int(self.absorb_frames), int(self.learn_frames), int(self.reveal_frames))


def fuse_masks(verdict, colour_mask=None):
    """
    Return the foreground where depth says so, and the colour mask where depth cannot tell.

    Parameters
    ----------
    verdict : ndarray (h, w) uint8
        :meth:`DepthBackground.update`'s verdict.
    colour_mask : ndarray (h, w) or None
        The colour detector's mask (non-zero foreground) at the verdict's
        size; None in depth-only mode (unknown pixels are then background).

    Returns
    -------
    mask : ndarray (h, w) bool

    """
    fused = verdict == FOREGROUND
    if colour_mask is not None:
        fused |= (verdict == UNKNOWN) & (np.asarray(colour_mask) > 0)
    return fused
