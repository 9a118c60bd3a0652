# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""A single background thread that runs one window solve at a time (no ROS import)."""

import logging
import threading

_LOG = logging.getLogger(__name__)


class SolveWorker:
    """
    Run ``solve(job)`` in one daemon thread, at most one job at a time; never die.

    There is no queue: :meth:`submit` refuses a job while another runs, so a
    burst of frames can never pile up solves; the caller simply submits the
    next snapshot when the next solve is due. ``on_done(job, result)`` or
    ``on_error(job, exception)`` run in the worker thread; an exception in
    ``on_done`` goes to ``on_error`` too. An exception raised by ``on_error``
    itself is logged and counted (:attr:`callback_errors`). Whatever happens,
    the job ends: :attr:`busy` is cleared and the thread takes the next job
    (a thread killed by something that is not an ``Exception`` is replaced at
    the next :meth:`submit`). ``initializer()``, if given, runs first in every
    thread the worker starts (per-thread settings such as the kernels' thread
    count); an exception from it is logged, and the thread solves without it.
    """

    def __init__(self, solve, on_done, on_error, name='dgmod-solver', initializer=None):
        self._solve = solve
        self._on_done = on_done
        self._on_error = on_error
        self._initializer = initializer
        self._name = name
        self._condition = threading.Condition()
        self._job = None
        self._busy = False
        self._stopping = False
        self.callback_errors = 0
        self.last_callback_error = ''
        self._thread = None
        self._start_thread()

    def _start_thread(self):
        self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
        self._thread.start()

    @property
    def busy(self):
        """Tell whether a job is queued or running."""
        with self._condition:
            return self._busy

    def submit(self, job):
        """Hand over a job; return False (and drop it) if one is already in hand."""
        with self._condition:
            if self._busy or self._stopping:
                return False
            if not self._thread.is_alive():
                self._start_thread()
            self._job = job
            self._busy = True
            self._condition.notify()
            return True

    def wait_idle(self, timeout=None):
        """Block until no job is in hand; return False on timeout."""
        with self._condition:
            return self._condition.wait_for(lambda: not self._busy, timeout)

    def stop(self, timeout=1.0):
        """Ask the thread to finish after the current job and join it."""
        with self._condition:
            self._stopping = True
            self._condition.notify_all()
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _run(self):
        if self._initializer is not None:
            try:
                self._initializer()
            except Exception as error:  # noqa: B902 - logged; the thread still solves
                _LOG.error('solve thread initializer raised %r', error, exc_info=error)
        while True:
            with self._condition:
                self._condition.wait_for(lambda: self._job is not None or self._stopping)
                if self._stopping:
                    return
                job, self._job = self._job, None
            try:
                self._run_job(job)
            finally:
                with self._condition:
                    self._busy = False
                    self._condition.notify_all()

    def _run_job(self, job):
        try:
            result = self._solve(job)
        except Exception as error:  # noqa: B902 - reported, never kills the thread
            self._report(job, error)
            return
        try:
            self._on_done(job, result)
        except Exception as error:  # noqa: B902 - likewise
            self._report(job, error)

    def _report(self, job, error):
        try:
            self._on_error(job, error)
        except Exception as failure:  # noqa: B902 - the last line of defence
            with self._condition:
                self.callback_errors += 1
                self.last_callback_error = f'{type(failure).__name__}: {failure}'
            _LOG.error('solve error handler raised %r while reporting %r', failure, error,
                       exc_info=failure)
