# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The detector node's per-frame rules (no ROS import).

:class:`EncodingWatch` decides the restart of the window on an encoding
change (same size, other meaning: colour to depth, say);
:func:`mask_frame` masks one frame in the node's ``solve_mode`` and, in
``async`` mode, hands a due window solve to the
:class:`~dgmod_ros.solve_worker.SolveWorker`; :func:`solve_job` is the
worker's job, :func:`solve_thread_settings` its thread's set-up.
"""

from .core.numba_setup import use_threads
from .core.runtime import yield_to_compute

# Nice increment of the solve thread (Linux: per thread). Where the cores
# are contended, the image callback, whose delay is every mask's, runs
# before the solve, whose delay only ages the background (docs/node.md,
# "scale:=1.0 on a loaded machine").
SOLVE_THREAD_NICENESS = 10


class EncodingWatch:
    """The encoding of the last frame, and whether the next one changes it."""

    def __init__(self):
        self.encoding = None

    def reset(self):
        """Forget the last encoding (a new detector: no restart is due)."""
        self.encoding = None

    def changed(self, encoding):
        """
        Take the next frame's encoding in; return the previous one if it differs, else None.

        A change restarts the window (the caller resets the detector). The
        first frame, and any after :meth:`reset`, changes nothing.
        """
        previous, self.encoding = self.encoding, encoding
        if previous is not None and encoding != previous:
            return previous
        return None


def mask_frame(detector, image, channel_order, value_range, solve_mode, worker, on_due=None):
    """
    Mask one frame; return ``(FrameResult, installed model or None)``.

    ``sync``: the detector's own :meth:`~StreamingDetector.process` solves in
    line. ``async``: the frame is masked at once (:meth:`push`, which
    installs a finished solve); a solve due then calls ``on_due()`` (the
    stats' wait starts) and, unless ``worker`` is busy, submits a job that
    names its detector, so the result is installed only there and only in
    the same configuration. Raises ValueError for a
    frame that cannot be used.
    """
    if solve_mode == 'sync':
        return detector.process(image, channel_order, value_range)
    # A solve left in flight by the sync mode is installed here.
    result = detector.push(image, channel_order, value_range)
    if detector.solve_due():
        if on_due is not None:
            on_due()
        if not worker.busy:
            worker.submit((detector, detector.snapshot()))
    return result, result.installed


def solve_job(job):
    """Solve a job of :func:`mask_frame` (in the worker's thread)."""
    detector, snapshot = job
    return detector.solve(snapshot)


def solve_thread_settings(threads):
    """Set up a solve thread: ``threads`` kernel threads, nice :data:`SOLVE_THREAD_NICENESS`."""
    use_threads(threads)
    yield_to_compute(SOLVE_THREAD_NICENESS)
