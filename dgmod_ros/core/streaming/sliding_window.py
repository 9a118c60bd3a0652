# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The sliding-window streaming detector that every window method runs in.

The node and the command line's ``stream`` mode both run this class, so the
masks of a bag replayed through the node equal the offline command's.
"""

import cv2
import numpy as np

from .buffer import FrameWindow, SceneChangeWatch
from .contract import StreamingDetector
from .fast_path import foreground_magnitude
from .results import FrameResult, WindowSnapshot
from .settings import assign_validated, check_window_parameters
from .window_solve import solve_window
from ..dgmod import DualGraphMOD
from ..masks import MaskRule
from ..preprocess import frame_columns, processing_shape


class SlidingWindowDetector(StreamingDetector):
    """
    Sliding-window separation with a fast path for every frame.

    A frame's mask never waits for a solve: :meth:`push` masks it from the
    background subspace of the last window solve
    (:mod:`~dgmod_ros.core.streaming.fast_path`) with the
    :class:`~dgmod_ros.core.masks.MaskRule`. Every ``stride`` buffered frames
    a solve of the whole window (any model with the ``fit(data, frame_shape,
    init)`` interface) refreshes that subspace; see
    :class:`~dgmod_ros.core.streaming.contract.StreamingDetector` for the
    protocol that lets it run in another thread.

    Parameters
    ----------
    model : estimator or None, default=None
        Object with ``fit(data, frame_shape, init=None)`` setting
        ``background_``, ``foreground_`` and optionally ``state_``,
        ``n_iter_``, ``info_``. None: :class:`DualGraphMOD` with ``tol=1e-3``
        and at most 5 sweeps per solve: every solve starts from the previous
        one, so sweeps add up over overlapping windows (``docs/solver.md``
        has the measured effect of the sweep count).
    window : int, default=30
        Frames ``m`` kept in the window.
    stride : int, default=10
        Buffered frames between solves.
    scale : float, default=0.5
        Processing scale in (0, 1]; masks come back at the input size.
    color : {'gray', 'rgb'}, default='gray'
        'rgb' solves each channel and fuses the magnitudes by their maximum.
    mask_rule : MaskRule or None
        None: ``MaskRule()``.
    motion_threshold : float, default=0.0
        Frames whose mean absolute difference to the last buffered frame is
        below this are masked but not buffered (the paper's motionless-frame
        rule, per pixel); 0 buffers every frame.
    min_frames : int, default=5
        Frames needed before the first solve. Until then masks come from the
        per-pixel median of the buffered frames.
    basis_rank : int, default=2
        Largest number of background components the fast path projects on.
        The window's background can hold slow foreground (a person lingering
        for part of the window shows up as a weak extra component); keeping
        the dominant components keeps the scene and its illumination.
    global_change_fraction : float, default=0.7
        When the fast path marks more than this fraction of two consecutive
        frames as foreground, the scene itself changed (lights switched, an
        exposure jump, a bumped camera): the window is restarted from those
        two frames, so masks are all-foreground for at most two frames. A
        global gain change needs no restart (the projection absorbs it). 1.0
        disables the rule; a person filling more of the view than this
        fraction would also restart the window.

    Attributes
    ----------
    buffer_ : FrameWindow
        The buffered frames.
    background_model_ : BackgroundModel or None
        The last installed solve.
    shape_, input_shape_ : tuple or None
        Processing shape (rows, cols, C) and input (rows, cols).
    scene_changes_, solves_discarded_ : int
        Window restarts by the scene-change rule; solved models refused by
        :meth:`install` (another detector's or an earlier configuration's).

    """

    def __init__(self, model=None, window=30, stride=10, scale=0.5, color='gray',
                 mask_rule=None, motion_threshold=0.0, min_frames=5, basis_rank=2,
                 global_change_fraction=0.7):
        self.model = model
        self.window = window
        self.stride = stride
        self.scale = scale
        self.color = color
        self.mask_rule = mask_rule
        self.motion_threshold = motion_threshold
        self.min_frames = min_frames
        self.basis_rank = basis_rank
        self.global_change_fraction = global_change_fraction
        self._validated = False

    # ------------------------------------------------------------- set-up
    def validate(self):
        """Check the parameters; raise ``ValueError`` naming the bad one."""
        check_window_parameters(self)
        self._validated = True
        return self

    def _ensure_started(self):
        if not self._validated:
            self.validate()
        if not hasattr(self, 'model_'):
            self._build_helpers()
        if not hasattr(self, 'buffer_'):
            self.scene_changes_ = 0
            self.solves_discarded_ = getattr(self, 'solves_discarded_', 0)
            self.reset()

    def _build_helpers(self):
        self.model_ = (self.model if self.model is not None
                       else DualGraphMOD(tol=1e-3, max_iter=5))
        self.mask_rule_ = self.mask_rule or MaskRule()

    def configure(self, **params):
        """
        Change parameters while running, keeping the buffered frames.

        The whole change is validated first; on ``ValueError`` nothing changes.
        Solves in flight are discarded when they come back; a new estimator
        class starts cold. A new ``window``
        keeps the newest frames; a new ``scale`` resamples the buffered frames
        and drops the background model until the next solve, which is then
        due at once; a new ``color`` restarts the window (grey frames cannot
        become colour); model and mask parameters take effect at the next solve.
        """
        old = assign_validated(self, params)
        if not hasattr(self, 'buffer_'):
            return self
        self._new_generation()
        old_model = self.model_
        self._build_helpers()
        if type(self.model_) is not type(old_model):
            self.drop_warm_start()          # another estimator's iterates are no start
        if 'color' in params and params['color'] != old['color']:
            self.reset()
            return self
        self.buffer_.resize(int(self.window))
        if ('scale' in params and params['scale'] != old['scale']
                and self.input_shape_ is not None):
            rows, cols = processing_shape(self.input_shape_, self.scale)
            shape = (rows, cols, self.shape_[2])
            self.buffer_.rescale(self.shape_, shape)
            self.shape_ = shape
            self.background_model_ = None
            self.background_pending_ = False
        return self

    def reset(self):
        """Forget every buffered frame and the background model."""
        self._new_generation()
        self.buffer_ = FrameWindow(int(self.window))
        self.scene_watch_ = SceneChangeWatch()
        self.background_model_ = None
        self.background_pending_ = False
        self.input_shape_ = None
        self.shape_ = None
        self.next_id_ = 0
        self.since_solve_ = 0

    # ------------------------------------------------------------- per frame
    def _ingest(self, frame, channel_order, value_range):
        self._ensure_started()
        columns, shape = frame_columns(frame, self.scale, self.color, channel_order,
                                       value_range)
        input_shape = np.shape(frame)[:2]
        reset = self.shape_ is not None and (shape != self.shape_
                                             or input_shape != self.input_shape_)
        if reset:
            self.reset()
        self.shape_ = shape
        self.input_shape_ = input_shape
        frame_id = self.next_id_
        self.next_id_ += 1
        buffered = not self.buffer_.is_motionless(columns, self.motion_threshold)
        if buffered:
            self.buffer_.append(columns, frame_id)
            self.since_solve_ += 1
        return FrameResult(mask=None, magnitude=None, frame_id=frame_id, buffered=buffered,
                           reset=reset, model_ready=False), columns

    def _finish(self, pending):
        result, columns = pending
        result.magnitude, threshold = foreground_magnitude(
            columns, self.shape_, self.background_model_, self.buffer_.stack(columns),
            self.mask_rule_)
        result.mask = self.mask_rule_.apply(result.magnitude, threshold, self.input_shape_)
        result.model_ready = self.background_model_ is not None
        result.new_background = self.background_pending_
        self.background_pending_ = False
        if len(self.buffer_) and self.scene_watch_.observe(result.mask,
                                                           self.global_change_fraction):
            self._restart_from_newest(SceneChangeWatch.FRAMES)
        return result

    def _restart_from_newest(self, count):
        """Keep only the newest ``count`` frames and drop the model (a scene change)."""
        self._new_generation()
        self.since_solve_ = self.buffer_.keep_newest(count)
        self.background_model_ = None
        self.background_pending_ = False
        self.scene_changes_ += 1

    def background_image(self):
        """Return the newest background column of the last solve at the input size, or None."""
        if not hasattr(self, 'buffer_') or self.background_model_ is None:
            return None
        rows, cols = self.input_shape_
        background = cv2.resize(self.background_model_.background, (cols, rows),
                                interpolation=cv2.INTER_LINEAR)
        return background.reshape(rows, cols, -1)

    def status(self):
        """Return the window's figures for diagnostics."""
        self._ensure_started()
        return {'window_frames': len(self.buffer_),
                'model_ready': self.background_model_ is not None,
                'scene_changes': self.scene_changes_}

    # ------------------------------------------------------------- solves
    def solve_due(self):
        """Tell whether a window solve should run now."""
        self._ensure_started()
        if self.background_model_ is None:
            return len(self.buffer_) >= self.min_frames
        return self.since_solve_ >= self.stride

    def snapshot(self):
        """Copy the window for a solve and restart the stride count."""
        self._ensure_started()
        if len(self.buffer_) < 2:
            raise ValueError('a window solve needs at least 2 buffered frames')
        data = self.buffer_.stack()                            # (C, n, m)
        self.since_solve_ = 0
        return WindowSnapshot(data=data, shape=self.shape_, first_id=self.buffer_.first_id,
                              last_id=self.buffer_.last_id, previous=self.background_model_,
                              model=self.model_, mask_rule=self.mask_rule_,
                              basis_rank=int(self.basis_rank), ticket=self._ticket())

    def solve(self, snapshot):
        """
        Separate a snapshot into a :class:`BackgroundModel` (see :func:`solve_window`).

        Reads nothing but the snapshot, so it may run in another thread while
        frames are pushed (the estimator in the snapshot must not be shared
        with another concurrent solve).
        """
        return solve_window(snapshot)

    def drop_warm_start(self):
        """Make the next solve start cold (after a failed one), keeping the fast path."""
        if getattr(self, 'background_model_', None) is not None:
            self.background_model_.states = []

    def _install(self, model):
        self.background_model_ = model
        self.background_pending_ = True
