# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""What the streaming detectors hand out: frame results, window snapshots, solved models."""

from dataclasses import dataclass, field

import numpy as np


class SolverFailure(RuntimeError):
    """A window solve produced non-finite values or raised; the old model stays."""


@dataclass
class FrameResult:
    """
    Outcome of pushing one frame.

    Attributes
    ----------
    mask : ndarray uint8 (input rows, input cols)
        0 or 255.
    magnitude : ndarray float32
        Foreground magnitude at the processing size.
    frame_id : int
        Sequence number of the frame since the last reset.
    buffered : bool
        False if the frame was not kept in a window (motionless, or a
        detector without a window).
    reset : bool
        True if the detector restarted at this frame (size change).
    model_ready : bool
        False while warming up (no background model yet).
    new_background : bool
        True when :meth:`StreamingDetector.background_image` has a background
        not announced before: the one rule for publishing backgrounds.
    solve_error : str or None
        Set when the solve whose turn it was at this frame failed.
    installed : BackgroundModel or None
        The solved model installed right before this frame was masked.

    """

    mask: np.ndarray
    magnitude: np.ndarray
    frame_id: int
    buffered: bool
    reset: bool
    model_ready: bool
    new_background: bool = False
    solve_error: str = None
    installed: object = None


@dataclass(frozen=True)
class SolveTicket:
    """
    Which detector, in which configuration, started a solve.

    ``owner`` is an opaque token unique to one detector object; ``generation``
    counts that detector's reconfigurations and restarts. A solved model is
    installed only by the detector and generation on its ticket.
    """

    owner: object
    generation: int


@dataclass
class SolveInFlight:
    """
    A started solve waiting for its frame (the install rule of the contract).

    ``future`` (a ``concurrent.futures.Future``) gives the model or raises
    :class:`SolverFailure`; ``frames_left`` counts down the frames until it is
    installed.
    """

    ticket: SolveTicket
    future: object
    frames_left: int


@dataclass
class WindowSnapshot:
    """
    A copy of the buffered window and everything its solve needs.

    Solving reads nothing else, so it is safe in another thread while frames
    are pushed and parameters change.
    """

    data: object                # (C, n, m) float32 (any memory order), or its columns: ``window``
    shape: tuple                # (rows, cols, C)
    first_id: int
    last_id: int
    previous: object            # BackgroundModel or None, for the warm start
    model: object               # the estimator configured when the snapshot was taken
    mask_rule: object           # likewise the MaskRule
    basis_rank: int             # likewise the fast path's basis size
    ticket: SolveTicket = None
    observed: np.ndarray = None  # (n, m) bool: entries the noise levels count; None: all
    holds_fill: bool = True     # a column of the window's fill is still in it
    first_column: int = None    # admission count of the oldest column (warm-start shift)
    decision: str = 'global'    # likewise the decision rule ('adaptive' needs pixel noise)
    noise_source: str = 'solve'  # likewise the residual the pixel noise comes from
    doubtful_floor: float = 1.0  # likewise how far consecutive differences lower a level
    offset_k: float = 0.0       # likewise the offset rule's multiple (pixel_k; 0: off)
    solve_shape: tuple = None   # (rows, cols, C) the window is solved at; None: ``shape``
    refit_background: bool = False  # refit each pixel's series on the solve's factors
    warm_start: bool = True     # start from ``previous``'s iterates where they fit
    column_cache: object = None  # ColumnCache of the columns in ``data`` (solve_resolution)
    healed: np.ndarray = None   # (n,) bool: pixels the window took a frame at since the last solve

    def window(self):
        """
        Return the stacked frames (C, n, m), stacked on first use if ``data`` holds columns.

        A detector may hand over the buffered columns, a sequence of (C, n)
        arrays that nothing writes to, instead of the stacked window: the
        copy (27 MB at 640 x 480) then runs in the solve's thread, not in
        the per-frame path that took the snapshot. Columns are stacked
        frames-major, (m, C, n) in memory, and the window is the (C, n, m)
        view of that: a stack along the new last axis is a strided scatter
        that took ten times as long (docs/node.md), and the solve reads the
        window frame by frame anyway.
        """
        if not isinstance(self.data, np.ndarray):
            self.data = np.stack(self.data, axis=0).transpose(1, 2, 0)
        return self.data

    def frames(self):
        """Return the window frame by frame, each (C, n): the buffered columns, stacked or not."""
        if isinstance(self.data, np.ndarray):
            return self.data.transpose(2, 0, 1)
        return self.data

    @property
    def width(self):
        """Return how many frames the window holds (stacking nothing)."""
        return self.data.shape[2] if isinstance(self.data, np.ndarray) else len(self.data)


@dataclass
class BackgroundModel:
    """
    What a window solve leaves for the fast path.

    Attributes
    ----------
    basis : ndarray (C, n, r)
        Orthonormal basis of each channel's background columns.
    background : ndarray (rows, cols, C)
        The newest background column as an image at the processing size.
    mean_background : ndarray (rows, cols, C)
        The window's mean background (the paper's background estimate).
    threshold : float or None
        Mask threshold estimated from this window's residual (the global
        rule); None when solved for a per-pixel decision, which reads ``noise``.
    shape : tuple
        (rows, cols, C) processing shape the model belongs to.
    first_id, last_id : int
        Sequence numbers of the window's oldest and newest frame.
    states : list
        Per-channel solver states for a warm start (None if the method has none).
    seconds, iterations, info : float, int, int
        Cost and outcome of the solve.
    ticket : SolveTicket or None
        The snapshot's ticket: who may install this model.
    noise : ndarray (n,) or None
        Each pixel's noise level (the adaptive decision), None for the global rule.
    chroma_noise : ndarray (n,) or None
        Each pixel's chromaticity noise level (the lighting test, colour only).
    known_noise : ndarray (n,) or None
        Each pixel's last level read from a window of conditional admissions
        in which it was observed (NaN: none yet;
        :func:`~dgmod_ros.core.streaming.noise_levels.known_levels`); None
        before the first such window and for the global rule.
    first_column : int or None
        Admission count of the window's oldest column.
    solve_shape : tuple or None
        (rows, cols, C) the window was solved at (the warm start's size);
        None: ``shape``.
    fit_basis : ndarray or None
        ``basis`` at the pixels the fast path's IRLS sweeps weigh
        (:func:`~.fast_path.sampled_basis`); None: formed per frame.

    """

    basis: np.ndarray
    background: np.ndarray
    mean_background: np.ndarray
    threshold: float
    shape: tuple
    first_id: int
    last_id: int
    states: list = field(default_factory=list)
    seconds: float = 0.0
    iterations: int = 0
    info: int = 0
    ticket: SolveTicket = None
    noise: np.ndarray = None
    first_column: int = None
    chroma_noise: np.ndarray = None
    known_noise: np.ndarray = None
    solve_shape: tuple = None
    fit_basis: np.ndarray = None
