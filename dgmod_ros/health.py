# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The detector node's health rules (no ROS import).

:class:`ForegroundWatch` counts jumps of the foreground share between
consecutive masks (the camera moved, the lights changed);
:func:`node_figures` assembles the figures ``/diagnostics`` reports and
:func:`problems` turns them into the status message (WARN with the
problems, else OK). The node only wraps them in ``DiagnosticStatus``.
"""

import numpy as np

#: The status message when nothing is wrong.
ALL_WELL = 'masks published for every frame'


class ForegroundWatch:
    """
    The foreground share of the last mask, and the jumps of it beyond a threshold.

    A jump is a change of the share between consecutive masks by more than
    ``threshold`` (a fraction of the frame); :meth:`reset` (the window
    restarted) forgets the last share, so the first mask after it is no jump.
    """

    def __init__(self):
        self.share = None       # of the last mask, fraction of the frame
        self.jumps = 0
        self._reported = 0

    def reset(self):
        """Forget the last share (the next mask starts afresh)."""
        self.share = None

    def observe(self, mask, threshold):
        """
        Take the next mask in; return ``(previous, share)`` if the share jumped, else None.

        ``mask``: any array, nonzero where foreground; ``threshold``: the
        ``foreground_jump`` parameter.
        """
        share = float(np.count_nonzero(mask)) / mask.size
        previous, self.share = self.share, share
        if previous is not None and abs(share - previous) > threshold:
            self.jumps += 1
            return previous, share
        return None

    def unreported(self):
        """Return the jumps since the last call (each jump is reported once)."""
        new, self._reported = self.jumps - self._reported, self.jumps
        return new


def jump_warning(previous, share):
    """Return the log line of a foreground jump from share ``previous`` to ``share``."""
    return (f'foreground share jumped from {previous:.0%} to {share:.0%} of the frame: '
            'camera moved or lights changed? (~/reset_background restarts the window)')


def node_figures(stats, lifecycle_state, frames_ignored, watch, detector_status,
                 depth=None, depth_only=False, worker=None):
    """
    Return the node's figures as a dict, in the order ``/diagnostics`` lists them.

    ``stats``: the :class:`~dgmod_ros.stats.DetectorStats`; ``watch``: the
    :class:`ForegroundWatch`; ``detector_status()``: the detector's
    ``status()``, or None without a detector (called once, where its
    figures go: the caller takes the detector's lock there); ``depth``,
    ``worker``: the node's, or None where it has none.
    """
    figures = stats.snapshot()
    figures['lifecycle_state'] = lifecycle_state
    figures['frames_ignored_inactive'] = frames_ignored
    figures['foreground_jumps'] = watch.jumps
    if watch.share is not None:
        figures['foreground_share'] = round(watch.share, 4)
    if depth is not None:
        figures.update(depth.statistics())
    status = detector_status()
    if status is not None:
        figures.update(status)
    else:
        figures.update(window_frames=0, model_ready=False)
    if depth_only:
        figures['model_ready'] = figures.get('depth_model_ready', False)
    if worker is not None:
        figures['worker_callback_errors'] = worker.callback_errors
    return figures


def problems(figures, lifecycle_state, solve_overdue, solve_timeout, malformed_depth=0,
             new_jumps=0, foreground_jump=0.0):
    """
    Return the problems the figures show, in the order the status message names them.

    ``solve_overdue``: the stats' solve-timeout rule for ``solve_timeout``
    s; ``malformed_depth``: depth images and camera infos dropped;
    ``new_jumps``: foreground jumps not yet reported (beyond the
    ``foreground_jump`` fraction). No problem: OK.
    """
    found = []
    if figures['frames_dropped']:
        found.append(f"{figures['frames_dropped']} frames dropped")
    if figures['solve_failures']:
        found.append(f"{figures['solve_failures']} solves failed")
    if lifecycle_state != 'active':
        found.append(f'{lifecycle_state}: not masking frames')
    elif not figures['model_ready']:
        found.append('warming up: no background model yet')
    if solve_overdue:
        found.append(f"no window solve finished for {figures['solve_wait_s']:.0f} s "
                     f'while frames arrive (solve_timeout {solve_timeout} s): the '
                     'background is frozen')
    if malformed_depth:
        found.append(f'{malformed_depth} malformed depth images or camera infos dropped')
    if new_jumps:
        found.append(f'foreground share jumped {new_jumps} times '
                     f'by more than {foreground_jump:.0%} of the frame '
                     '(camera moved, lights?)')
    return found


def status_message(found):
    """Return the status message of the problems ``found`` (:data:`ALL_WELL` if none)."""
    return '; '.join(found) or ALL_WELL
