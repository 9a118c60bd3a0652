# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The window the model solves: frames spread over a long span, foreground left out.

A window of ``m`` consecutive frames forgets in ``m`` frames: a person who
stands still for half a window is learned into the background ``L`` and
vanishes from the masks. :class:`BackgroundMemory` fills with ``m``
consecutive frames (the first solves separate what moves in them) and then
admits a frame only every ``spacing`` frames, settling to ``kept`` columns
that span ``kept * spacing`` frames, and it admits a frame
conditionally: where the frame's own mask says foreground, the column holds
the current background instead of the frame (the pixel counts as not
observed). A person who stops therefore stays foreground, while everything
the masks call background keeps refreshing the model. While the window
fills, frames go in as they are, their foreground only marked as not
observed, so that the noise levels of the first solves leave out a person
the first masks saw. A pixel that has been
foreground for ``absorb_frames`` frames in a row is admitted as it is, so an
object that stays (or a mistake of the masks) joins the background after
about ``absorb_frames + kept * spacing / 2`` frames, when the l1 fit lets the
majority of the window win.

How many columns the full window keeps is how many admissions of what the
masks call background it takes to outvote what the window learnt. A person in
view from the first frame is in every column of the fill; the place behind
them enters as they move (or heals, below) and must become the majority. The
fill's consecutive frames are what the first solves need, but they are one
second of a scene, not ``m`` independent views of it: after the fill they
leave two at a time until ``kept`` columns are left.

What the masks miss is learnt, and learning it hides it further: a slow
walker whose legs fall below the threshold enters the window at every
admission, the window's residual there grows, and with it the pixel's noise
level. :func:`held_pixels` therefore keeps out, with each blob of the mask,
the pixels that are away from the background by a lower multiple of their
noise level and changing or only lately away (something passing), and admits
those that have been away for long without changing (the rim of a ghost
that the held-still rule released).

A ghost the blob tests dropped would heal only as fast as admissions replace
the window's columns (a window of 30 columns 10 frames apart holds the
departed object for 150 frames as the l1 majority, 10 columns for 50). Where the place behind
has held still (the sliding-window detector's ``_note_healing``),
:meth:`BackgroundMemory.overwrite` puts the frame there into every column
at the next admission, the way ViBe and SuBSENSE re-seed the samples of a
pixel found to be a ghost, and the next solve starts there from the data.
"""

from collections import deque

import numpy as np

from .buffer import FrameWindow


class BackgroundMemory(FrameWindow):
    """
    The window's columns, admitted every ``spacing`` frames, with their observed pixels.

    Parameters
    ----------
    capacity : int
        Frames the window fills with, admitted one after the other so that
        the first solves have frames to work on.
    spacing : int
        Frames between admissions once the window is full (1: every frame,
        the plain sliding window).
    kept : int or None
        Columns the full window settles to (at most ``capacity``; None:
        ``capacity``). Each admission after the fill drops the oldest column,
        and one more while the window holds more than ``kept`` (the fill's
        consecutive frames leave two at a time) or none while it holds fewer.

    """

    def __init__(self, capacity, spacing=1, kept=None):
        super().__init__(capacity)
        self.spacing = int(spacing)
        self.kept = self.capacity if kept is None else min(int(kept), self.capacity)
        self._observed = deque(maxlen=int(capacity))
        self.admitted = 0               # columns admitted so far (warm-start bookkeeping)
        self.last_admitted_id = None
        self.filling = True             # every frame is admitted until the window is full
        self.fill_end = None            # admission count at which the last fill ended

    @property
    def first_column(self):
        """Return the admission count of the oldest column (warm-start shifts)."""
        return self.admitted - len(self)

    @property
    def holds_fill(self):
        """Tell whether the window still holds a column of its fill (admitted unconditionally)."""
        return self.filling or self.first_column < self.fill_end

    def _note_fill_end(self):
        if self.filling and len(self) >= self.capacity:
            self.fill_end = self.admitted
        self.filling = self.filling and len(self) < self.capacity

    def wants(self, frame_id):
        """Tell whether the frame ``frame_id`` is due for admission."""
        if self.filling or self.last_admitted_id is None:
            return True
        return frame_id - self.last_admitted_id >= self.spacing

    def append(self, columns, frame_id, observed=None):
        """Admit a frame's columns (C, n); ``observed`` (n,) bool marks the pixels noise counts."""
        if not self.filling:
            # One column closer to ``kept`` with each admission.
            for _ in range(1 + int(np.sign(len(self) - self.kept))):
                for store in (self._ids, self._frames, self._observed):
                    store.popleft()
        super().append(columns, frame_id)
        self._observed.append(observed)
        self.admitted += 1
        self.last_admitted_id = frame_id
        self._note_fill_end()

    def observed(self):
        """Return the observed pixels of the columns (n, m) bool, or None when all are."""
        if all(o is None for o in self._observed):
            return None
        n = self._frames[0].shape[1]
        full = np.ones(n, dtype=bool)
        return np.stack([full if o is None else o for o in self._observed], axis=1)

    def overwrite(self, pixels, values):
        """
        Put ``values`` (C, n) at ``pixels`` (k,) int into every column: the window heals there.

        The columns are replaced, not written (:meth:`columns` hands them out
        as never written), and the pixels count as observed in each.
        """
        for store in (self._frames, self._observed):
            old = list(store)
            store.clear()
            for entry in old:
                if entry is not None:
                    entry = entry.copy()
                    if entry.ndim == 2:
                        entry[:, pixels] = values[:, pixels]
                    else:
                        entry[pixels] = True
                store.append(entry)

    def clear(self):
        """Forget every column (the admission count goes on); the window fills again."""
        for store in (self._ids, self._frames, self._observed):
            store.clear()
        self.last_admitted_id = None
        self.filling = True
        self.fill_end = None

    def keep_newest(self, count):
        """Drop all but the newest ``count`` columns; return how many remain."""
        recent = list(zip(self._ids, self._frames, self._observed))[-count:]
        for store in (self._ids, self._frames, self._observed):
            store.clear()
        for frame_id, columns, observed in recent:
            self._ids.append(frame_id)
            self._frames.append(columns)
            self._observed.append(observed)
        return len(recent)

    def resize(self, capacity, kept=None):
        """Keep at most ``capacity`` columns (the newest) and settle to ``kept`` from now on."""
        super().resize(capacity)
        self._observed = deque(self._observed, maxlen=int(capacity))
        self.kept = self.capacity if kept is None else min(int(kept), self.capacity)
        self._note_fill_end()

    def rescale(self, old_shape, new_shape):
        """Resample every column to ``new_shape``; every pixel counts as observed again."""
        super().rescale(old_shape, new_shape)
        self._observed = deque([None] * len(self), maxlen=self.capacity)


def conditional_columns(columns, background, foreground, foreground_age, absorb_frames,
                        replace=True):
    """
    Return the columns to admit and their observed pixels (conditional update).

    The observed pixels are those the noise levels count
    (:func:`~dgmod_ros.core.streaming.noise_levels.pixel_noise`): the frame's
    own pixels where its mask called it background.

    Parameters
    ----------
    columns, background : ndarray (C, n)
        The frame and what goes in place of its foreground (its background
        fit without that foreground) at the processing size.
    foreground : ndarray (n,) bool
        The frame's foreground at the processing size (already dilated by the caller).
    foreground_age : ndarray (n,) int
        Consecutive frames each pixel has been foreground.
    absorb_frames : int
        Foreground older than this is admitted as it is.
    replace : bool or ndarray (n,) bool
        Where to put the background in place of the foreground: True
        everywhere, False nowhere (the frame goes in as it is, its
        foreground only not observed), or the pixels marked (the window
        still filling: only where something came in under a model).

    """
    held = foreground & (foreground_age < absorb_frames)
    if not held.any():
        return columns, None
    replaced = held & replace
    if replaced.any():
        columns = np.where(replaced[None, :], background, columns)
    return columns, ~held


def held_pixels(mask, away, changing, away_age, young_frames):
    """
    Return the pixels (n,) bool the conditional update keeps out of the window.

    The frame's mask, and the pixels away from their background that are
    changing (against a frame a few frames before) or have been away for
    fewer than ``young_frames`` frames: something passing that the mask
    missed (a slow walker's limbs, a reflection). A pixel away from its
    background for longer and not changing (the rim of a ghost that the
    held-still rule released) is admitted, so the window heals there.

    Parameters
    ----------
    mask : ndarray (rows, cols) uint8
        The frame's foreground at the processing size.
    away, changing : ndarray (n,) bool
        Pixels over a multiple of their noise level from the background, and
        from the earlier frame.
    away_age : ndarray (n,) int
        Consecutive frames each pixel has been ``away``.
    young_frames : int
        Frames a pixel away from its background is held even if it does not
        change.

    """
    return (mask.ravel() > 0) | (away & (changing | (away_age < young_frames)))
