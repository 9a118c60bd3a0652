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

**When a solve is installed.** :meth:`~StreamingDetector.process` installs
the solve of a snapshot taken at frame ``t`` right before masking frame
``t + solve_lag`` (``solve_lag`` frames, a detector parameter, at most its
``stride``; 0 for detectors without it), whether the solve ran in line or in another thread
(``executor``): if it is not finished by then, ``process`` waits for it. The
masks therefore never depend on how fast a solve runs, and a solve has
``solve_lag`` frames of time to run beside the per-frame work. With an
executor, a solve whose window is already final before it is due (no frame
will be admitted in between, :meth:`~StreamingDetector.frames_until_final_solve`)
starts at once and is installed at the frame it would have been: more time
beside the per-frame work, the same masks.
:meth:`~StreamingDetector.push` keeps the same rule without waiting: a solve
finished late is installed at the first frame after it finished.

Every snapshot carries a :class:`~.results.SolveTicket`: the detector object
that took it and its configuration generation (raised by every
:meth:`~StreamingDetector.configure`, :meth:`~StreamingDetector.reset` and
window restart). ``install`` accepts a model only with the current ticket, so a
solve that comes back after the detector was replaced, reconfigured or
restarted is discarded and counted (``solves_discarded_``), never installed.
"""

from abc import ABC, abstractmethod
from concurrent.futures import Future

from .results import SolveInFlight, SolverFailure, SolveTicket


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

        A solve started with :meth:`track_solve` is installed before the frame
        is masked once its ``solve_lag`` frames have passed and it has
        finished (``result.installed``, ``result.solve_error``).

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
        pending = self._ingest(frame, channel_order, value_range)
        installed, error = self._install_finished(wait=False)
        result = self._finish(pending)
        result.installed, result.solve_error = installed, error
        return result

    def process(self, frame, channel_order='rgb', value_range=None, executor=None):
        """
        Take a frame in, start the solve when due, install by the lag rule, mask the frame.

        The frame is taken in first, so a solve due now sees the window as it
        is before this frame is admitted. The solve of a snapshot taken at
        frame ``t`` is installed right before frame ``t + solve_lag`` is
        masked (with ``solve_lag`` 0, this frame), waiting for it if needed:
        the same masks whether the solve runs in line or in ``executor``, and
        whatever its speed. A failed solve keeps the previous model, makes the
        next solve start cold and is reported in ``result.solve_error``.

        Parameters
        ----------
        frame, channel_order, value_range
            As for :meth:`push`.
        executor : concurrent.futures.Executor or None
            Runs the solves (one worker is enough: one solve is in flight at a
            time); None solves in line.

        Returns
        -------
        result : FrameResult
        solved : BackgroundModel or None
            The model installed before this frame was masked, if any.

        """
        pending = self._ingest(frame, channel_order, value_range)
        installed, error = self._install_finished(wait=True)
        ahead = 0 if executor is None or self.solve_due() else self.frames_until_final_solve()
        if self.solve_due() or ahead:
            snapshot = self.snapshot(ahead)
            if executor is None:
                future = Future()
                try:
                    future.set_result(self.solve(snapshot))
                except SolverFailure as failure:
                    future.set_exception(failure)
            else:
                future = executor.submit(self.solve, snapshot)
            self.track_solve(snapshot, future, ahead)
            if self.solve_in_flight_.frames_left <= 0:
                installed, error = self._install_finished(wait=True, count=False)
        result = self._finish(pending)
        result.installed, result.solve_error = installed, error
        return result, installed

    # ------------------------------------------------------------- install rule
    def frames_until_final_solve(self):
        """
        Return in how many frames the next solve is due if its window is already final, else 0.

        A positive answer lets :meth:`process` start that solve now, in its
        executor: the snapshot taken now equals the one it would take then
        (no frame is admitted in between), so the solve is the same and
        is installed at the same frame. Detectors without window solves
        answer 0.
        """
        return 0

    def track_solve(self, snapshot, future, ahead=0):
        """
        Register the solve of ``snapshot``, running in ``future``, for the install rule.

        The next :meth:`push` or :meth:`process` calls count frames against
        it and install its model (or report its :class:`SolverFailure`) once
        ``ahead + solve_lag`` frames have passed (``ahead``: the frames by
        which an early start precedes the frame the solve is due). The first
        solve (no model yet: masks come from the warm-up) is installed without
        lag. One solve is in flight at a time.
        """
        lag = int(getattr(self, 'solve_lag', 0)) if snapshot.previous is not None else 0
        stride = getattr(self, 'stride', None)
        if stride is not None:          # one solve in flight: the next is due at the stride
            lag = min(lag, int(stride))
        self.solve_in_flight_ = SolveInFlight(ticket=snapshot.ticket, future=future,
                                              frames_left=int(ahead) + lag)

    def solve_in_flight(self):
        """Tell whether a started solve waits to be installed (no new solve is due till then)."""
        return getattr(self, 'solve_in_flight_', None) is not None

    def _install_finished(self, wait, count=True):
        """
        Count this frame against the solve in flight; install it when its frame has come.

        Returns ``(installed model or None, error message or None)``. With
        ``wait`` a solve whose frame has come is waited for; without, a solve
        still running stays in flight (installed at the first frame after it
        ends).
        """
        in_flight = getattr(self, 'solve_in_flight_', None)
        if in_flight is None:
            return None, None
        if count:
            in_flight.frames_left -= 1
        if in_flight.frames_left > 0 or not (wait or in_flight.future.done()):
            return None, None
        self.solve_in_flight_ = None
        try:
            model = in_flight.future.result()
        except SolverFailure as failure:
            if in_flight.ticket == self._ticket():
                self.drop_warm_start()
            return None, str(failure)
        return (model if self.install(model) else None), None

    @abstractmethod
    def background_image(self):
        """Return the current background, float [0, 1], (h, w, C) at the input size, or None."""

    @abstractmethod
    def processing_size(self):
        """Return the (rows, cols) the per-frame path runs at for the frames seen, or None."""

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
    def snapshot(self, ahead=0):
        """
        Copy what the due solve needs (a WindowSnapshot with the current ticket).

        ``ahead`` (from :meth:`frames_until_final_solve`) takes the snapshot of
        a solve due that many frames later; the stride count restarts there.
        """

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
        """Invalidate every ticket handed out so far (a solve in flight is discarded)."""
        self._ticket()
        self.generation_ += 1
        if getattr(self, 'solve_in_flight_', None) is not None:
            self.solve_in_flight_ = None
            self.solves_discarded_ = getattr(self, 'solves_discarded_', 0) + 1
