# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""OpenCV's per-frame subtractors: a streaming detector and a window method."""

import cv2
import numpy as np

from .masks import clean_mask
from .preprocess import processing_shape, resize, to_float_channels, to_uint8
from .streaming.contract import StreamingDetector
from .streaming.results import FrameResult, SolverFailure
from .streaming.settings import assign_validated, COLOR, SCALE
from .validation import NON_NEGATIVE_INTEGER, Options, POSITIVE_INTEGER, validate_params
from .window_data import check_window_data

_FACTORIES = {
    'mog2': cv2.createBackgroundSubtractorMOG2,
    'knn': cv2.createBackgroundSubtractorKNN,
}


class OpenCVSubtractor(StreamingDetector):
    """
    OpenCV MOG2 or KNN with default settings, as a ROS user would run it.

    A :class:`~dgmod_ros.core.streaming.contract.StreamingDetector` without
    window solves: the subtractor updates its model with every frame, so
    :meth:`solve_due` is always False, :meth:`install` refuses every model and
    :meth:`drop_warm_start` does nothing. Its output is already a mask: 255 is
    foreground, 127 (a shadow) is not. The mask is resized to the input size
    and cleaned with the same morphology as
    :class:`~dgmod_ros.core.masks.MaskRule`.

    Parameters
    ----------
    kind : {'mog2', 'knn'}, default='mog2'
        Which subtractor.
    scale : float, default=0.5
        Processing scale.
    processing_pixels : int, default=25600
        Largest processing size (pixels), as the window detector's.
    color : {'gray', 'rgb'}, default='gray'
        Feed luma or the three colour channels.
    morph_size : int, default=3
        Opening and closing kernel; 0 or 1 disables it.
    stride : int, default=10
        Frames between new background images (``FrameResult.new_background``
        is set on every ``stride``-th frame), as a window method gives one per
        solve.

    References
    ----------
    .. [1] Z. Zivkovic, "Improved adaptive Gaussian mixture model for background
       subtraction", ICPR 2004.
    .. [2] Z. Zivkovic, F. van der Heijden, "Efficient adaptive density
       estimation per image pixel for the task of background subtraction",
       Pattern Recognition Letters 27(7), 2006.

    """

    _parameter_constraints = {'kind': [Options(*_FACTORIES)], 'scale': SCALE,
                              'processing_pixels': POSITIVE_INTEGER, 'color': COLOR,
                              'morph_size': NON_NEGATIVE_INTEGER, 'stride': POSITIVE_INTEGER}

    def __init__(self, kind='mog2', scale=0.5, processing_pixels=25600, color='gray',
                 morph_size=3, stride=10):
        self.kind = kind
        self.scale = scale
        self.processing_pixels = processing_pixels
        self.color = color
        self.morph_size = morph_size
        self.stride = stride

    def validate(self):
        """Check the parameters; raise ``ValueError`` naming the bad one."""
        return validate_params(self)

    def reset(self):
        """Start a new background model."""
        self._new_generation()
        self.subtractor_ = _FACTORIES[self.kind]()
        self.input_shape_ = None
        self.processing_shape_ = None
        self.next_id_ = 0

    def configure(self, **params):
        """Change parameters (validated first); the background model restarts."""
        assign_validated(self, params)
        self.reset()
        return self

    def _ensure_started(self):
        if not hasattr(self, 'subtractor_'):
            self.validate().reset()
            self.solves_discarded_ = getattr(self, 'solves_discarded_', 0)

    def _ingest(self, frame, channel_order, value_range):
        self._ensure_started()
        frame = np.asarray(frame)
        if frame.ndim < 2 or frame.shape[0] == 0 or frame.shape[1] == 0:
            raise ValueError(f'frame must be a non-empty image, got shape {frame.shape}')
        channels = to_float_channels(frame, channel_order, self.color, value_range)
        reset = self.input_shape_ is not None and frame.shape[:2] != self.input_shape_
        if reset:
            self.reset()
        self.input_shape_ = frame.shape[:2]
        self.processing_shape_ = processing_shape(frame.shape[:2], self.scale,
                                                  int(self.processing_pixels))
        small = resize(channels, self.processing_shape_)
        image = to_uint8(small)
        if image.ndim == 3 and image.shape[2] == 3:
            image = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
        raw = self.subtractor_.apply(image)
        frame_id = self.next_id_
        self.next_id_ += 1
        return raw, frame_id, reset

    def _finish(self, pending):
        raw, frame_id, reset = pending
        mask = np.where(raw == 255, np.uint8(255), np.uint8(0))
        if mask.shape != self.input_shape_:
            mask = cv2.resize(mask, self.input_shape_[::-1], interpolation=cv2.INTER_NEAREST)
        return FrameResult(mask=clean_mask(mask, self.morph_size),
                           magnitude=raw.astype(np.float32) / 255.0, frame_id=frame_id,
                           buffered=False, reset=reset, model_ready=True,
                           new_background=(frame_id + 1) % int(self.stride) == 0)

    def background_image(self):
        """Return OpenCV's background image as floats in [0, 1], (h, w, C) at the input size."""
        if getattr(self, 'input_shape_', None) is None:
            return None
        image = self.subtractor_.getBackgroundImage().astype(np.float32) / 255.0
        image = image[:, :, None] if image.ndim == 2 else image[:, :, ::-1]
        rows, cols = self.input_shape_
        return cv2.resize(image, (cols, rows), interpolation=cv2.INTER_LINEAR).reshape(
            rows, cols, -1)

    def processing_size(self):
        """Return the (rows, cols) the subtractor runs at, or None before the first frame."""
        return getattr(self, 'processing_shape_', None)

    def status(self):
        """Return the subtractor's figures for diagnostics (it has no window)."""
        self._ensure_started()
        return {'window_frames': 0, 'model_ready': self.input_shape_ is not None,
                'scene_changes': 0}

    def solve_due(self):
        """Return False: the subtractor updates its model with every frame."""
        return False

    def snapshot(self, ahead=0):
        """Refuse: a subtractor has no window to solve."""
        raise ValueError(f'{self.kind} updates its model with every frame; it has no window '
                         'to solve')

    def solve(self, snapshot):
        """Refuse any snapshot: a subtractor solves no windows."""
        raise SolverFailure(f'{self.kind} solves no windows')

    def drop_warm_start(self):
        """Do nothing: there is no warm start."""

    def _install(self, model):
        """Never reached: no snapshot of this detector carries a ticket to install with."""


class OpenCVWindowModel:
    """
    An OpenCV subtractor as a window method (``batch`` mode).

    Every window trains a fresh subtractor on all its frames, then masks each
    frame with learning switched off, so every mask uses the whole window, as
    the window methods do. ``foreground_`` is 1 where OpenCV says foreground
    (255) and 0 elsewhere, so any mask threshold below 1 reproduces its mask.

    Parameters
    ----------
    kind : {'mog2', 'knn'}, default='mog2'
        Which subtractor.

    """

    def __init__(self, kind='mog2'):
        self.kind = kind

    def fit(self, data, frame_shape, init=None):
        """Train on the window's frames, then mask each (``init`` is unused)."""
        if self.kind not in _FACTORIES:
            raise ValueError(f"kind must be 'mog2' or 'knn', got {self.kind!r}")
        data = check_window_data(data, frame_shape)
        rows, cols = frame_shape
        frames = to_uint8(data).T.reshape(-1, rows, cols)
        subtractor = _FACTORIES[self.kind]()
        for frame in frames:
            subtractor.apply(frame)
        masks = np.stack([subtractor.apply(frame, learningRate=0.0) == 255 for frame in frames])
        self.foreground_ = masks.reshape(len(frames), -1).T.astype(np.float32)
        background = subtractor.getBackgroundImage().astype(np.float32).ravel() / 255.0
        self.background_ = np.repeat(background[:, None], len(frames), axis=1)
        self.n_iter_ = 1
        self.info_ = 0
        return self
