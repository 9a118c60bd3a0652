# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The one contract of every streaming detector the node and ``dgmod separate`` run.

A streaming detector masks each frame at once (:meth:`~StreamingDetector.push`)
and may keep its background model right with window solves that run apart
from the frames: :meth:`~StreamingDetector.solve_due` says when,
:meth:`~StreamingDetector.snapshot` copies what a solve needs,
:meth:`~StreamingDetector.solve` (any thread) separates it and
:meth:`~StreamingDetector.install` makes the result the model.
:meth:`~StreamingDetector.process` runs all of it in line. A detector
without window solves implements the same methods: its ``solve_due`` is
always False and ``install`` refuses every model.

Every snapshot carries a :class:`~.results.SolveTicket`: the detector object
that took it and its configuration generation (raised by every
:meth:`~StreamingDetector.configure`, :meth:`~StreamingDetector.reset` and
window restart). ``install`` accepts a model only with the current ticket, so a
solve that comes back after the detector was replaced, reconfigured or
restarted is discarded and counted (``solves_discarded_``), never installed.
"""

from abc import ABC, abstractmethod

from .results import SolverFailure, SolveTicket


class StreamingDetector(ABC):
    """Base class and contract of the streaming detectors (scikit-learn style)."""

    # ------------------------------------------------------------- set-up
    @abstractmethod
    def validate(self):
        """Check the parameters; raise ``ValueError`` naming the bad one; return self."""

    @abstractmethod
    def configure(self, **params):
        """
        Change parameters while running; validated first, nothing changes on ``ValueError``.

        Must call :meth:`_new_generation`, so that solves in flight are discarded.
        Returns self.
        """

    @abstractmethod
    def reset(self):
        """Forget every frame and the background model (and start a new generation)."""

    # ------------------------------------------------------------- per frame
    @abstractmethod
    def _ingest(self, frame, channel_order, value_range):
        """Take one frame in (validate, convert, buffer); return what :meth:`_finish` needs."""

    @abstractmethod
    def _finish(self, pending):
        """Mask the frame taken in by :meth:`_ingest` with the current model; a FrameResult."""

    def push(self, frame, channel_order='rgb', value_range=None):
        """
        Mask one frame at once from the current model; never runs a window solve.

        Parameters
        ----------
        frame : ndarray (h, w) or (h, w, 3|4)
            Any integer or float image; see
            :func:`~dgmod_ros.core.preprocess.to_float_channels`.
        channel_order : {'rgb', 'bgr'}
            Order of a colour frame's channels.
        value_range : float or None
            Full-scale pixel value; None uses the dtype's range.

        Returns
        -------
        FrameResult

        Raises
        ------
        ValueError
            For a frame that cannot be used (the detector is unchanged).

        """
        return self._finish(self._ingest(frame, channel_order, value_range))

    def process(self, frame, channel_order='rgb', value_range=None):
        """
        Take a frame in, solve in line when due, then mask it (the synchronous path).

        The frame is buffered first, so a solve due now includes it, and it is
        masked with the freshest model. A failed solve keeps the previous
        model, makes the next solve start cold and is reported in
        ``result.solve_error``.

        Returns
        -------
        result : FrameResult
        solved : BackgroundModel or None
            The model of the solve run for this frame, if one was due and installed.

        """
        pending = self._ingest(frame, channel_order, value_range)
        solved, error = None, None
        if self.solve_due():
            try:
                solved = self.solve(self.snapshot())
            except SolverFailure as failure:
                error = str(failure)
                self.drop_warm_start()
            else:
                if not self.install(solved):
                    solved = None
        result = self._finish(pending)
        result.solve_error = error
        return result, solved

    @abstractmethod
    def background_image(self):
        """Return the current background, float [0, 1], (h, w, C) at the input size, or None."""

    @abstractmethod
    def status(self):
        """
        Return a dict of figures for diagnostics.

        Keys: ``window_frames``, ``model_ready``, ``scene_changes``.
        """

    # ------------------------------------------------------------- solves
    @abstractmethod
    def solve_due(self):
        """Tell whether a window solve should run now."""

    @abstractmethod
    def snapshot(self):
        """Copy what the due solve needs (a WindowSnapshot with the current ticket)."""

    @abstractmethod
    def solve(self, snapshot):
        """
        Separate a snapshot into a BackgroundModel; reads nothing but the snapshot.

        Raises
        ------
        SolverFailure
            When the solve raises or returns non-finite values.

        """

    @abstractmethod
    def drop_warm_start(self):
        """Make the next solve start cold (after a failed one), keeping the fast path."""

    def install(self, model):
        """
        Make a solved model the background if its ticket is this detector's current one.

        Returns
        -------
        bool
            False (and ``solves_discarded_`` counts it) for a model solved for
            another detector or an earlier configuration.

        """
        if model is None or model.ticket != self._ticket():
            self.solves_discarded_ = getattr(self, 'solves_discarded_', 0) + 1
            return False
        self._install(model)
        return True

    @abstractmethod
    def _install(self, model):
        """Make ``model`` (checked to be this generation's) the fast path's background."""

    # ------------------------------------------------------------- tickets
    def _ticket(self):
        """Return the ticket of the current configuration."""
        if not hasattr(self, 'owner_token_'):
            self.owner_token_ = object()      # identity only: unique to this detector
            self.generation_ = 0
        return SolveTicket(self.owner_token_, self.generation_)

    def _new_generation(self):
        """Invalidate every ticket handed out so far."""
        self._ticket()
        self.generation_ += 1
