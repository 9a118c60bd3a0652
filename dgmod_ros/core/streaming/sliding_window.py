# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The sliding-window streaming detector that every window method runs in.

The node and the command line's ``stream`` mode both run this class, so the
masks of a bag replayed through the node equal the offline command's.
"""

from collections import deque

import cv2
import numpy as np

from .background_memory import BackgroundMemory, conditional_columns, held_pixels
from .blobs import BlobMotion, blobs_of_at_least
from .buffer import SceneChangeWatch
from .contract import StreamingDetector
from .decision import adaptive_mask
from .fast_path import robust_projection
from .ghost import ghost_labels, ghost_parts
from .held_foreground import consecutive_frames, moved_inside, still_blob_pixels
from .holes import closed_and_filled
from .kernels.warmup_background import entry_medians
from .lines import processing_pixels_of, without_lines
from .noise_levels import warmup_noise
from .photometric import LightingTest
from .results import FrameResult, WindowSnapshot
from .settings import assign_validated, WINDOW_CONSTRAINTS
from .solve_resolution import ColumnCache, solve_shape
from .upsizing import to_input_size
from .window_solve import solve_window
from ..dgmod import DualGraphMOD
from ..masks import MaskRule
from ..preprocess import frame_columns, processing_shape
from ..validation import validate_params

# Share of outliers past which an l1 fit is pulled by them (the median's breakdown point).
_L1_BREAKDOWN = 0.5
# Frames back to the frame that tells whether a blob is still (the ghost test).
_GHOST_LAG = 5
# Growth of the foreground before the conditional update (processing pixels).
_BORDER_KERNEL = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
# Largest share of a blob's pixels that may change for the blob to count as still.
_STILL_SHARE = 0.01
# A pixel and its eight neighbours: the first frame is settled where all held still.
_NEIGHBOURS = np.ones((3, 3), np.uint8)


def _change(columns, other):
    """Return each pixel's distance (n,) to ``other``: the largest over the channels."""
    return np.abs(columns - other).max(axis=0)


class SlidingWindowDetector(StreamingDetector):
    """
    Sliding-window separation with a fast path for every frame.

    A frame's mask never waits for a solve: :meth:`push` projects it onto the
    background subspace of the last window solve
    (:mod:`~dgmod_ros.core.streaming.fast_path`) and decides each pixel
    against its own noise level
    (:mod:`~dgmod_ros.core.streaming.decision`; ``decision='global'``: the
    :class:`~dgmod_ros.core.masks.MaskRule`). The frame then enters the window
    if due (:mod:`~dgmod_ros.core.streaming.background_memory`: every
    ``memory_spacing`` frames, its foreground replaced by the background).
    Every ``stride`` frames a solve of the whole window (any model with the
    ``fit(data, frame_shape, init)`` interface) refreshes that subspace; see
    :class:`~dgmod_ros.core.streaming.contract.StreamingDetector` for the
    protocol that lets it run in another thread.

    Parameters
    ----------
    model : estimator or None, default=None
        Object with ``fit(data, frame_shape, init=None)`` setting
        ``background_``, ``foreground_`` and optionally ``state_``,
        ``n_iter_``, ``info_``. None: :class:`DualGraphMOD` with ``tol=1e-3``
        and at most 3 sweeps per solve, each solve started from its window's
        data (``warm_start``); the refit takes only the solve's temporal
        factors and its foreground (``docs/results.md`` has the measured
        effect of the sweep count).
    window : int, default=30
        Frames ``m`` the window fills with, one after the other: the first
        solves separate what moves in them.
    stride : int, default=10
        Frames between solves.
    scale : float, default=0.5
        Processing scale in (0, 1] of the per-frame path (projection,
        decision, the buffered window), up to ``processing_pixels``; masks
        come back at the input size. The window solve runs at this size
        too, up to ``solve_pixels``.
    processing_pixels : int, default=25600
        Largest frame (pixels) the per-frame path runs at: a larger one
        (after ``scale``) is scaled down to at most this many pixels, same
        aspect. The per-frame rules reach over neighbourhoods of a fixed
        number of processing pixels (the median and the Potts field's 5 x
        5, the texture's patches, the border kept out of the window), so a
        scene means the same to them whatever the camera's resolution; the
        default is the largest processing size of the sequences the
        defaults were chosen on (352 x 288 at ``scale`` 0.5), so a 640 x
        480 camera runs at 184 x 138 (``docs/results.md``).
    color : {'gray', 'rgb'}, default='rgb'
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
    memory_spacing : int, default=10
        Frames between admissions to the full window, so that it spans
        ``memory_columns * memory_spacing`` frames; 1 (with
        ``memory_columns >= window``) is the window of consecutive frames.
    memory_columns : int, default=10
        Columns the full window settles to (at most ``window``): each
        admission after the fill drops the oldest column, and one more while
        the window holds more (the fill's frames leave two at a time). Each
        column weighs ``1 / memory_columns`` in the solve's l1 fit, so this
        sets how many admissions of what the masks call background it takes
        to replace what the window learnt: a person in view from the first
        frame is learnt, and the place behind them, seen as they move, must
        outvote them (``docs/results.md``).
    conditional_update : bool, default=True
        Admit a frame with its foreground (the mask, dilated by 5 x 5 at the
        processing size) replaced by the background, the frame's projection
        on the basis fit without that foreground (fit with it, it takes in
        part of the person), so that a person who stops is not learned into
        the background. While the window fills, only a body that came in
        under a model is held out (foreground where the model called the
        pixel background before in the fill, in blobs of at least
        ``line_pixels`` camera pixels: a person who walks up in the first
        second); the rest goes in as it is, its foreground only left out of
        the noise levels (a person in view from the first frame, the ghost
        of where he stood, leaves that were calm while the model was learnt;
        see :meth:`_replaced`).
    hold_changes : bool, default=False
        The conditional update also keeps out the pixels over ``pixel_k / 2``
        noise levels from the background that are as far from the frame 5
        frames before or have been away for fewer than ``still_frames``
        frames (something passing that the mask missed: learnt, it raises the
        pixel's noise level and hides it further; see
        :func:`~dgmod_ros.core.streaming.background_memory.held_pixels`).
        Off by default: on a background that moves all the time (leaves) it
        holds out the observations that teach the window the texture's
        spread, and the leaves come through (``docs/results.md``).
    absorb_frames : int, default=5400
        Foreground older than this many frames is admitted as it is (a left
        object joins the background after about ``absorb_frames +
        memory_columns * memory_spacing / 2`` frames).
    decision : {'adaptive', 'uniform', 'global'}, default='adaptive'
        'adaptive': each pixel against ``pixel_k`` times its own noise level;
        'uniform': the same with the frame's typical noise level for all
        pixels; 'global': the ``mask_rule`` (one threshold, morphology).
    noise_source : {'solve', 'projection', 'least_squares', 'max'}, default='solve'
        The window residual each pixel's noise level is read from: the
        solve's ``D - L``, each column against its robust or least-squares
        projection on the fast path's basis (the distance the per-frame
        decision thresholds), or the larger of the 'solve' and 'projection'
        levels.
    doubtful_floor : float, default=0.5
        A pixel the window's masks called foreground in more than half of its
        columns (a person in view while the window filled) reads its noise
        level from the differences of consecutive columns where that is lower
        than the level of all its columns, but not below this share of it
        (:mod:`~dgmod_ros.core.streaming.noise_levels`; 'adaptive', 'uniform').
        1 reads the level of all its columns.
    pixel_k : float, default=6.0
        Multiple of the noise level that makes a pixel foreground ('adaptive',
        'uniform'); also the multiple of a pixel's column-to-column level past
        which its level in the window is an offset of the model, not noise
        (:mod:`~dgmod_ros.core.streaming.noise_levels`).
    median_size : int, default=5
        Median filter of the adaptive decision at the processing size (odd;
        1 disables it).
    ghost_test : bool, default=True
        Drop still blobs whose outline is an edge of the background rather
        than of the frame (something in the window's frames has left; see
        :func:`~dgmod_ros.core.streaming.ghost.ghost_blobs`), and the still
        parts of blobs along most of whose outline the background crosses an
        edge that the frame does not (a ghost joined to what is leaving it:
        :func:`~dgmod_ros.core.streaming.ghost.ghost_parts`); their pixels
        enter the window as they are, which heals the background.
    still_frames : int, default=15
        Drop pixels that have been in a still blob (at most 1 % of its pixels
        changed by more than ``pixel_k / 2`` noise levels against the frame
        5 frames before) for this many consecutive frames; they enter the
        window as they are (ghosts that uncover texture, see
        :mod:`~dgmod_ros.core.streaming.held_foreground`). A blob seen to
        come in (most of its pixels moved while foreground) is never still:
        a person who stops stays foreground for ``absorb_frames``. The
        pixels a blob test drops that have held still for this many frames
        (at least 5) heal the window: every column takes the frame there,
        and the next solve starts from it
        (:meth:`~dgmod_ros.core.streaming.background_memory.BackgroundMemory.overwrite`).
        0 disables.
    line_pixels : int, default=100
        A blob that holds no 3 x 3 square of foreground at the processing
        size is a line, not a body (the rim of a light that grew with the
        exposure, a cable's shadow); one that covers at least this many of
        the camera's pixels, an obstacle to a planner, is left out of the
        published mask but still kept out of the window
        (:mod:`~dgmod_ros.core.streaming.lines`; 'adaptive', 'uniform'). 0
        keeps every blob. Also the fewest camera pixels of a body that the
        filling window holds out where it came in under a model
        (``conditional_update``; 0: every blob).
    fill_holes : bool, default=True
        Close the published mask with the Potts field's neighbourhood (a
        gap the field opened in an outline is bridged) and fill its holes:
        background pixels enclosed by a body's outline, or by it and one
        side of the frame (a flat coat whose colour the window has seen
        there, a body cut by the frame's edge; background that reaches two
        sides or a corner is the scene's:
        :mod:`~dgmod_ros.core.streaming.holes`; 'adaptive', 'uniform'). The
        window keeps the unfilled decision.
    mrf_beta : float, default=2.0
        > 0: the adaptive decision is a Potts field over the ``pixel_k``-sigma
        rule, coupling 5 x 5 neighbours with this weight (log-odds per
        neighbour; :mod:`~dgmod_ros.core.streaming.coherence`), in place of
        the median filter; 0: threshold and median filter.
    chroma_cue, texture_cue : bool, default=True
        Drop the candidate pixels whose change light explains (a shadow, a
        reflection: see :mod:`~dgmod_ros.core.streaming.photometric`), judged
        by their chromaticity, their LBSP texture or both, and their
        brightness ratio ('adaptive', 'uniform'); both False keeps every
        candidate.
    texture_bits : int, default=8
        Largest LBSP Hamming distance of a change of light.
    moving_texture_k : float, default=2.0
        > 0: a pixel whose LBSP texture differs from the background's in at
        least ``moving_texture_bits`` bits and that changed against the frame
        5 frames before is foreground from this multiple of its noise level
        instead of ``pixel_k`` ('adaptive', 'uniform'; see
        :func:`~dgmod_ros.core.streaming.decision.moving_texture_k`); 0
        disables.
    moving_texture_bits : int, default=16
        Fewest differing LBSP bits of a changed texture.
    solve_lag : int, default=5
        Frames between a solve's snapshot and its install (at most
        ``stride``; a larger lag waits ``stride`` frames): the solve of the
        window taken at frame ``t`` becomes the model right before frame
        ``t + solve_lag`` is masked, so it may run beside ``solve_lag``
        frames of per-frame work with the same masks whatever its speed (the
        install rule of
        :class:`~dgmod_ros.core.streaming.contract.StreamingDetector`). The
        default is about when the node's solve thread, which installs a
        solve when it ends, has one ready at 30 frames/s, so that replays
        and the offline stream mode see what the live node does.
    solve_pixels : int, default=19200
        Largest frame (pixels) the window solve runs at. A larger solve
        (after ``solve_scale``) is scaled down to at most this many pixels,
        same aspect, and the full-size background carried from the solve's
        temporal factors (:mod:`~dgmod_ros.core.streaming.solve_resolution`);
        the default, 160 x 120, binds only where ``processing_pixels`` is
        raised above 76800 (a processing size of 320 x 240 at the default
        ``solve_scale``), so that such a size costs about the same solve.
    solve_scale : float, default=0.5
        Scale in (0, 1] of the window solve against the processing size
        (before the ``solve_pixels`` cap): the solve fixes the background's
        temporal factors, which a coarser frame carries as well, and the
        full-size fit fixes each pixel (``docs/results.md`` has the measured
        effect); 1 solves at the processing size.
    warm_start : bool, default=False
        Start each window solve from the previous solve's iterates, shifted
        by the columns the window moved on, instead of from its data: the
        sweeps add up over overlapping windows, and so does what the first
        windows learnt (a person in view from the first frame stays in the
        iterates after the columns that held them have left; measured in
        ``docs/results.md``).
    refit_background : bool, default=True
        The window's background is each pixel's own time series fit on the
        solve's leading ``basis_rank`` temporal factors, the entries the
        solve called foreground (over 3 noise levels) held out
        (:func:`~dgmod_ros.core.streaming.solve_resolution.carry_backgrounds`),
        also when the solve runs at the processing size: a short solve's
        ``L`` keeps a smear of what moved through the window, and its
        residual, which sets the noise levels, is then inflated where people
        passed. False: the solve's own ``L`` where the solve is not scaled
        down.

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

    _parameter_constraints = WINDOW_CONSTRAINTS

    def __init__(self, model=None, window=30, stride=10, scale=0.5, processing_pixels=25600,
                 color='rgb', mask_rule=None, motion_threshold=0.0, min_frames=5, basis_rank=2,
                 global_change_fraction=0.7, memory_spacing=10, memory_columns=10,
                 conditional_update=True, hold_changes=False, absorb_frames=5400,
                 decision='adaptive', noise_source='solve', doubtful_floor=0.5, pixel_k=6.0,
                 median_size=5, ghost_test=True, still_frames=15, line_pixels=100,
                 fill_holes=True, mrf_beta=2.0, chroma_cue=True, texture_cue=True,
                 texture_bits=8, moving_texture_k=2.0, moving_texture_bits=16, solve_lag=5,
                 solve_pixels=19200, solve_scale=0.5, warm_start=False, refit_background=True):
        self.model = model
        self.window = window
        self.stride = stride
        self.scale = scale
        self.processing_pixels = processing_pixels
        self.color = color
        self.mask_rule = mask_rule
        self.motion_threshold = motion_threshold
        self.min_frames = min_frames
        self.basis_rank = basis_rank
        self.global_change_fraction = global_change_fraction
        self.memory_spacing = memory_spacing
        self.memory_columns = memory_columns
        self.conditional_update = conditional_update
        self.hold_changes = hold_changes
        self.absorb_frames = absorb_frames
        self.decision = decision
        self.noise_source = noise_source
        self.doubtful_floor = doubtful_floor
        self.pixel_k = pixel_k
        self.median_size = median_size
        self.ghost_test = ghost_test
        self.still_frames = still_frames
        self.line_pixels = line_pixels
        self.fill_holes = fill_holes
        self.mrf_beta = mrf_beta
        self.chroma_cue = chroma_cue
        self.texture_cue = texture_cue
        self.texture_bits = texture_bits
        self.moving_texture_k = moving_texture_k
        self.moving_texture_bits = moving_texture_bits
        self.solve_lag = solve_lag
        self.solve_pixels = solve_pixels
        self.solve_scale = solve_scale
        self.warm_start = warm_start
        self.refit_background = refit_background
        self._validated = False

    # ------------------------------------------------------------- set-up
    def validate(self):
        """Check the parameters; raise ``ValueError`` naming the bad one."""
        validate_params(self)
        (self.mask_rule or MaskRule()).validate()
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
                       else DualGraphMOD(tol=1e-3, max_iter=3))
        self.mask_rule_ = self.mask_rule or MaskRule()
        self.lighting_ = (LightingTest(self.chroma_cue, self.texture_cue, int(self.texture_bits))
                          if self.chroma_cue or self.texture_cue else None)

    def configure(self, **params):
        """
        Change parameters while running, keeping the buffered frames.

        The whole change is validated first; on ``ValueError`` nothing changes.
        Solves in flight are discarded when they come back; a new estimator
        class starts cold. A new ``window`` keeps the newest frames; a new
        processing size (``scale``, ``processing_pixels``) resamples the
        buffered frames and drops the background model until the next solve,
        which is then due at once; a new ``color`` restarts the window (grey
        frames cannot become colour); model and mask parameters take effect
        at the next solve.
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
        self.buffer_.resize(int(self.window), int(self.memory_columns))
        self.buffer_.spacing = int(self.memory_spacing)
        if self.input_shape_ is None:
            return self
        rows, cols = processing_shape(self.input_shape_, self.scale, int(self.processing_pixels))
        shape = (rows, cols, self.shape_[2])
        if shape != self.shape_:
            self.buffer_.rescale(self.shape_, shape)
            self.shape_ = shape
            self.background_model_ = None
            self.background_pending_ = False
            self.recent_.clear()            # frames of the old size
            self._forget_pixel_histories()
        return self

    def _forget_pixel_histories(self):
        """Drop every per-pixel count and mark (a new size, a reset, a scene change)."""
        self.foreground_age_ = None
        self.still_age_ = None
        self.away_age_ = None
        self.entered_ = None
        self.heal_ = None
        self.healed_ = None
        self.uncovered_age_ = None
        self.previous_foreground_ = None
        self.still_value_ = None         # (C, n) each pixel's newest settled value
        self.still_known_ = None         # (n,) bool: the pixel has settled once
        self.moving_ = None              # (n,) bool: moving now, settled before
        self.held_still_ = None
        self.background_seen_ = None     # (n,) bool: background under a model in this fill

    def reset(self):
        """Forget every buffered frame and the background model."""
        self._new_generation()
        self.buffer_ = BackgroundMemory(int(self.window), int(self.memory_spacing),
                                        int(self.memory_columns))
        self.column_cache_ = ColumnCache()
        self._forget_pixel_histories()
        self.recent_ = deque(maxlen=_GHOST_LAG)
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
                                       value_range, int(self.processing_pixels))
        input_shape = np.shape(frame)[:2]
        reset = self.shape_ is not None and (shape != self.shape_
                                             or input_shape != self.input_shape_)
        if reset:
            self.reset()
        self.shape_ = shape
        self.input_shape_ = input_shape
        frame_id = self.next_id_
        self.next_id_ += 1
        self.since_solve_ += 1
        return FrameResult(mask=None, magnitude=None, frame_id=frame_id, buffered=False,
                           reset=reset, model_ready=False), columns

    def _background(self, columns):
        """Return the frame's background (C, n) and its noise level (n,) or mask threshold."""
        model = self.background_model_
        if model is None:
            # Warm-up: the per-pixel median of what is buffered is the background
            # (the frame itself while nothing is).
            buffered = self.buffer_.columns()
            background = entry_medians(buffered or (columns,))
            if self.decision == 'global':
                residual = columns - background
                return background, self.mask_rule_.estimate_threshold(
                    residual, self.buffer_.stack(columns))
            # The frame itself counts: with one frame buffered there is no other difference.
            return background, warmup_noise(buffered + (columns,))
        background = robust_projection(model.basis, columns, fit_basis=model.fit_basis)
        if self.decision == 'global':
            if model.threshold is None:     # solved for a per-pixel decision (switched since)
                return background, self.mask_rule_.threshold_from_noise(model.noise)
            return background, model.threshold
        if model.noise is None:             # solved under the global rule
            return background, model.threshold / self.mask_rule_.k
        return self._unpulled(model, columns, background), model.noise

    def _unpulled(self, model, columns, background):
        """
        Return ``background``, or the fit without the previous frame's foreground if that fits.

        An l1 fit breaks down once a person covers about half of the view:
        pulled towards him, it reads much of the frame as changed. Past
        ``global_change_fraction`` of the pixels the scene-change rule would
        restart the window from frames of the person, whose background is
        the person from then on; short of it, the pulled fit calls the place
        around him foreground. Where the whole frame's fit leaves more than
        half of the pixels off it by ``pixel_k`` noise levels (its breakdown
        point, or the scene-change share where that is lower), the fit is
        tried again without the pixels the previous frame called foreground.
        It is taken where it holds: no more than half of the pixels it was
        fit to are off it (a large person pulled the first fit; light
        switched over most of the view leaves the rest off as well), and it
        leaves fewer pixels off than the first. Only then, not in every fit:
        a region wrongly called foreground (a corner a change of light left
        as it was), left out of every fit, keeps itself foreground.
        """
        if self.previous_foreground_ is None:
            return background
        bound = self.pixel_k * np.asarray(model.noise, dtype=np.float32)
        pulled = np.count_nonzero(_change(columns, background) > bound)
        if pulled <= min(_L1_BREAKDOWN, self.global_change_fraction) * bound.size:
            return background
        rest = ~self.previous_foreground_
        unpulled = robust_projection(model.basis, columns, fit_basis=model.fit_basis,
                                     left_out=self.previous_foreground_)
        changed = _change(columns, unpulled) > bound
        # Taken where it holds on the pixels it was fit to (under the breakdown
        # point there) and leaves fewer pixels off than the whole frame's fit.
        holds = np.count_nonzero(changed & rest) <= _L1_BREAKDOWN * np.count_nonzero(rest)
        fewer = np.count_nonzero(changed) < pulled
        return unpulled if holds and fewer else background

    def _finish(self, pending):
        # The stages in the order a frame passes them (the package docstring's list).
        result, columns = pending
        background, level = self._background(columns)
        earlier = self.recent_[0][1] if len(self.recent_) == self.recent_.maxlen else None
        # Each pixel's change against the earlier frame, for the rules that ask it of pixels,
        # and the still test they share: within pixel_k / 2 noise levels of it.
        change = None if earlier is None else _change(columns, earlier)
        still = (None if change is None or self.decision == 'global'
                 else self._holds(change, level))
        foreground, changed = self._decide(result, columns, background, level, earlier, change,
                                           still)
        self._note_still(columns, still, level)
        result.buffered = self._admit(columns, background, foreground, result.frame_id,
                                      result.magnitude, level, still)
        self.previous_foreground_ = foreground.ravel() > 0
        self.recent_.append((result.frame_id, columns))
        result.model_ready = self.background_model_ is not None
        result.new_background = self.background_pending_
        self.background_pending_ = False
        if len(self.buffer_) and self.scene_watch_.observe(changed,
                                                           self.global_change_fraction):
            self._restart_from_newest(SceneChangeWatch.FRAMES)
        return result

    def _decide(self, result, columns, background, level, earlier, change, still):
        """
        Set ``result``'s magnitude and mask; return the processing-size foreground and the changes.

        The foreground (rows, cols) uint8 is what the window admits the frame
        with; the changes (n,) bool are what the scene-change rule counts.
        """
        rows, cols, _ = self.shape_
        if self.decision == 'global':
            result.magnitude = _change(columns, background).reshape(rows, cols)
            result.mask = self.mask_rule_.apply(result.magnitude, level, self.input_shape_)
            foreground = np.where(result.magnitude > level, np.uint8(255), np.uint8(0))
            return foreground, result.mask
        model = self.background_model_
        foreground, result.magnitude = adaptive_mask(
            columns, background, level, self.pixel_k, self.shape_, self.median_size,
            self.mrf_beta, self.lighting_, model.chroma_noise if model is not None else None,
            earlier, self.moving_texture_k, int(self.moving_texture_bits), change)
        # The scene-change rule counts every change, light included: after
        # the lights of most of the view switch, the lighting test would
        # hide the change while the window still holds the old light.
        changed = result.magnitude.ravel() > self.pixel_k * level
        if ((self.ghost_test or self.still_frames) and model is not None
                and earlier is not None):
            self._blob_rules(foreground, columns, background, level, earlier, change, still)
        # Lines leave, and holes join, what is published only: the window keeps
        # its own decision. Lines first: a ring of rim filled would be a body.
        line_size = processing_pixels_of(self.line_pixels, foreground.shape, self.input_shape_)
        published = without_lines(foreground, line_size)
        if self.fill_holes:
            published = closed_and_filled(published)
        result.mask = to_input_size(published, self.input_shape_)
        return foreground, changed

    def _blob_rules(self, foreground, columns, background, level, earlier, change, still):
        """Drop, in place, the ghost blobs and the blobs held still from ``foreground``."""
        # One labelling for both tests: the ghost test drops whole blobs.
        blobs = BlobMotion(foreground, columns, earlier, level)
        before = foreground > 0
        moved = moved_inside(foreground, self.foreground_age_, change, level, self.pixel_k,
                             _GHOST_LAG)
        self.entered_ = moved if self.entered_ is None else moved | self.entered_
        if self.ghost_test:
            blobs.drop(ghost_labels(blobs, foreground, columns, background, self.pixel_k),
                       foreground)
            # A ghost joined to what is leaving it is no still blob: its still part is judged.
            foreground[ghost_parts(foreground, columns, background, still, level,
                                   self.pixel_k)] = 0
        if self.still_frames:
            self._drop_still(foreground, columns, level, blobs)
        self._note_healing(columns, still, before, foreground)

    def _drop_still(self, foreground, columns, level, blobs):
        """Clear, in place, the pixels of ``foreground`` held still for ``still_frames``."""
        still = still_blob_pixels(foreground, columns, self.recent_[0][1], level,
                                  self.pixel_k / 2, _STILL_SHARE, blobs, self.entered_)
        self.still_age_ = consecutive_frames(self.still_age_, still)
        foreground[self.still_age_.reshape(foreground.shape) >= self.still_frames] = 0

    def _note_healing(self, columns, still, candidate, foreground):
        """
        Remember where the window should take the frame (blob tests' drops) and the frame there.

        ``candidate`` (rows, cols) bool is the foreground before the blob
        tests, ``foreground`` after them, ``still`` (n,) the pixels within
        ``pixel_k / 2`` noise levels of the frame ``_GHOST_LAG`` frames
        before. A pixel heals when a blob test dropped it, it was not seen to
        come in and it has held still for ``still_frames`` frames as a
        candidate: the place behind holds still, while leaves that a blob
        test dropped keep moving and keep their window.
        """
        holding = candidate.ravel() & ~self.entered_ & still
        self.uncovered_age_ = consecutive_frames(self.uncovered_age_, holding)
        uncovered = ((self.uncovered_age_ >= max(int(self.still_frames), _GHOST_LAG))
                     & (foreground.ravel() == 0))
        if not uncovered.any():
            return
        if self.heal_ is None:
            self.heal_ = (uncovered, columns.copy())
            return
        pixels, values = self.heal_
        pixels |= uncovered
        values[:, uncovered] = columns[:, uncovered]

    def _note_still(self, columns, still, level):
        """
        Keep each pixel's newest settled value and mark the pixels moving now.

        A pixel holds still (``still``) when its change against the frame
        ``_GHOST_LAG`` frames before is within ``pixel_k / 2`` noise levels
        (the still test of the blob rules); it has settled once it has held
        still for ``_GHOST_LAG`` frames in a row (the same value over twice
        the lag: a walker's plain trousers hold still for a frame or two, a
        place behind them that is uncovered settles). A pixel moving now
        (not holding still) that has settled before is admitted to the
        window with its settled value (:meth:`_admit`): motion is no
        evidence of the background, the way LaBGen picks, per pixel, the
        samples with the least motion. A pixel that never settled (leaves
        that never rest) is admitted as it is.

        The first frame is where each pixel has settled if it and its eight
        neighbours hold still into the second (within ``pixel_k / 2`` of
        its ``level``): a person in view from the first frame moves into
        places the first frame shows empty, and those places must not be
        learnt from the frames he covers them in. A pixel that changed at
        once (his moving limbs, leaves, a flickering codec) has not settled,
        nor has one beside such a change (the plain inside of a body whose
        outline moved, a leaf among leaves that did). Until the frame
        ``_GHOST_LAG`` frames before exists, the still test is against the
        first frame.
        """
        if self.decision == 'global':   # no noise levels: the window takes the frames as they are
            return
        if self.still_value_ is None:   # the first frame (or the first after a reset)
            self.still_value_ = columns.copy()
            return
        if self.still_known_ is None:   # the second: the first frame settled where it held
            held = self._holds(_change(columns, self.still_value_), level)
            held = held.reshape(self.shape_[:2])
            self.still_known_ = cv2.erode(held.astype(np.uint8), _NEIGHBOURS).ravel() > 0
        if still is None:               # before the lag's frame: against the first frame
            still = self._holds(_change(columns, self.recent_[0][1]), level)
            self.moving_ = ~still & self.still_known_
            return
        self.held_still_ = consecutive_frames(self.held_still_, still)
        settled = self.held_still_ >= _GHOST_LAG
        np.copyto(self.still_value_, columns, where=settled[None, :])
        self.still_known_ |= settled
        self.moving_ = ~still & self.still_known_

    def _holds(self, change, level):
        """Return the pixels (n,) bool whose ``change`` is within ``pixel_k / 2`` noise levels."""
        return change <= self.pixel_k / 2 * np.asarray(level, dtype=np.float32)

    def _admit(self, columns, background, foreground, frame_id, distance, level, still):
        """
        Put the frame into the window if due (conditionally); return whether it went in.

        ``still`` (n,) marks the pixels within ``pixel_k / 2`` noise levels of
        the frame ``_GHOST_LAG`` frames before (None while there is none).
        """
        self.foreground_age_ = consecutive_frames(self.foreground_age_, foreground > 0)
        if self.entered_ is not None:
            self.entered_ = self.entered_ & (self.foreground_age_ > 0)
        if self.hold_changes and self.decision != 'global':
            self.away_ = distance.ravel() > self.pixel_k / 2 * level
            self.away_age_ = consecutive_frames(self.away_age_, self.away_)
        if (not self.buffer_.wants(frame_id)
                or self.buffer_.is_motionless(columns, self.motion_threshold)):
            return False
        observed = None
        frame = columns
        if self.moving_ is not None:
            # What moves now is no evidence of the background: the window
            # takes the pixel's newest settled value there instead.
            columns = np.where(self.moving_[None, :], self.still_value_, columns)
        if self.conditional_update:
            model = self.background_model_
            held = foreground
            if (model is not None and not self.buffer_.filling and self.hold_changes
                    and self.decision != 'global'):
                held = self._held(foreground, still)
            # Dilated: a silhouette's border is foreground below the threshold.
            grown = cv2.dilate(held, _BORDER_KERNEL).ravel() > 0
            replace = self._replaced(foreground, grown)
            if np.any(replace):
                # In place of the foreground, the frame's projection on the
                # basis fit without it: fit to the whole frame the projection
                # takes in part of what stands there, and a person who stops
                # would seep into the window admission by admission; fit to
                # the rest it still follows the light.
                background = robust_projection(model.basis, frame, fit_basis=model.fit_basis,
                                               left_out=grown)
            columns, observed = conditional_columns(columns, background, grown,
                                                    self.foreground_age_, self.absorb_frames,
                                                    replace)
        if self.heal_ is not None:
            # The place behind what left, seen since the last admission: every
            # column holds it from now on, so the next solve learns it.
            pixels, values = self.heal_
            self.buffer_.overwrite(np.flatnonzero(pixels), values)
            self.healed_ = pixels if self.healed_ is None else self.healed_ | pixels
            self.heal_ = None
        self.buffer_.append(columns, frame_id, observed)
        return True

    def _replaced(self, foreground, grown):
        """
        Return where the conditional update puts the background in place of ``grown``.

        True (all of it) once the window is full, False (none) without a
        model. While the window fills, the pixels (n,) bool of ``grown``
        that a model called background in an earlier frame of the fill, in
        blobs of ``foreground`` (rows, cols) large enough to be an obstacle
        (``line_pixels`` of the camera's pixels, the 5 x 5 growth
        included): a body came in there under the model, and a person who
        walks up in the first second and stands would be learnt from the
        fill's frames as they are. The rest of the fill's foreground goes in
        as it is, only left out of the noise levels: a model learnt from a
        few frames holds whoever was in view from the first frame and calls
        the place behind him foreground where he stood (kept out, that ghost
        would keep itself in the window), and leaves that were calm while
        it was learnt flicker in specks (kept out, the window would never
        learn their spread). Notes where this frame is background, for the
        fill's frames after it.
        """
        if self.background_model_ is None:
            return False
        if not self.buffer_.filling:
            return True
        seen = self.background_seen_
        self.background_seen_ = ~grown if seen is None else seen | ~grown
        came_in = False if seen is None else grown & seen
        if not np.any(came_in):         # nothing to label: the frame goes in as it is
            return False
        size = processing_pixels_of(self.line_pixels, foreground.shape, self.input_shape_)
        bodies = cv2.dilate(blobs_of_at_least(foreground, size), _BORDER_KERNEL).ravel() > 0
        return came_in & bodies

    def _held(self, foreground, still):
        """Return the frame's pixels (rows, cols) uint8 that the conditional update keeps out."""
        changing = np.zeros_like(self.away_) if still is None else ~still
        held = held_pixels(foreground, self.away_, changing, self.away_age_,
                           self.still_frames)
        return np.where(held, np.uint8(255), np.uint8(0)).reshape(foreground.shape)

    def _restart_from_newest(self, count):
        """Restart the window from the newest ``count`` frames, drop the model (scene change)."""
        self._new_generation()
        self.buffer_.clear()
        for frame_id, columns in list(self.recent_)[-count:]:
            self.buffer_.append(columns, frame_id)
        self.since_solve_ = len(self.buffer_)
        self._forget_pixel_histories()
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

    def processing_size(self):
        """Return the (rows, cols) the per-frame path runs at, or None before the first frame."""
        shape = getattr(self, 'shape_', None)
        return None if shape is None else tuple(shape[:2])

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
        if self.solve_in_flight():
            return False
        if self.background_model_ is None:
            return len(self.buffer_) >= self.min_frames
        return self.since_solve_ >= self.stride

    def frames_until_final_solve(self):
        """
        Return in how many frames the next solve is due if no frame is admitted till then, else 0.

        Only with a model and a full window: admissions then come every
        ``memory_spacing`` frames at the earliest, so the window of the
        next solve is known as soon as the last admission before it is in.
        """
        self._ensure_started()
        if (self.solve_in_flight() or self.background_model_ is None
                or self.buffer_.filling or self.buffer_.last_admitted_id is None):
            return 0
        ahead = int(self.stride) - self.since_solve_
        # This frame's id; admissions happen when frames are masked (_finish).
        frame_id = self.next_id_ - 1
        next_admission = self.buffer_.last_admitted_id + self.buffer_.spacing
        return ahead if 0 < ahead and frame_id + ahead <= next_admission else 0

    def snapshot(self, ahead=0):
        """Copy the window for a solve and restart the stride count (``ahead`` frames later)."""
        self._ensure_started()
        if len(self.buffer_) < 2:
            raise ValueError('a window solve needs at least 2 buffered frames')
        # Stacked in the solve's thread (WindowSnapshot.window), not in this one.
        data = self.buffer_.columns()
        # An early start restarts the count at the frame the solve is due;
        # if it is discarded, the frames it took back are given back.
        self.early_credit_ = self.since_solve_ + int(ahead) if ahead else 0
        self.since_solve_ = -int(ahead)
        return WindowSnapshot(data=data, shape=self.shape_, first_id=self.buffer_.first_id,
                              last_id=self.buffer_.last_id, previous=self.background_model_,
                              model=self.model_, mask_rule=self.mask_rule_,
                              basis_rank=int(self.basis_rank), ticket=self._ticket(),
                              observed=self.buffer_.observed(),
                              holds_fill=self.buffer_.holds_fill,
                              first_column=self.buffer_.first_column, decision=self.decision,
                              noise_source=self.noise_source,
                              doubtful_floor=float(self.doubtful_floor),
                              offset_k=float(self.pixel_k),
                              solve_shape=solve_shape(self.shape_, int(self.solve_pixels),
                                                      float(self.solve_scale)),
                              refit_background=bool(self.refit_background),
                              warm_start=bool(self.warm_start),
                              column_cache=self.column_cache_, healed=self.healed_)
        self.healed_ = None

    def solve(self, snapshot):
        """
        Separate a snapshot into a :class:`BackgroundModel` (see :func:`solve_window`).

        Reads nothing but the snapshot, so it may run in another thread while
        frames are pushed (the estimator in the snapshot must not be shared
        with another concurrent solve).
        """
        return solve_window(snapshot)

    def _new_generation(self):
        if self.solve_in_flight() and getattr(self, 'early_credit_', 0):
            self.since_solve_ += self.early_credit_    # the early solve is due as before
        self.early_credit_ = 0
        super()._new_generation()

    def drop_warm_start(self):
        """Make the next solve start cold (after a failed one), keeping the fast path."""
        if getattr(self, 'background_model_', None) is not None:
            self.background_model_.states = []

    def _install(self, model):
        self.background_model_ = model
        self.background_pending_ = True
