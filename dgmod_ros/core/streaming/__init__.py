# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Streaming detection: a mask for every frame, window solves apart from the frames.

The path a frame takes, in order (:meth:`SlidingWindowDetector.process_frame`
and its ``_finish``), one module per stage:

1. :mod:`.buffer`: the frame joins the buffered frames of the window (their
   rescaling; the scene-change rule that restarts the window is the last step).
2. :mod:`.fast_path`: its background from the last solve, an l1 projection by
   IRLS (before the first solve: each pixel's median of the buffered frames).
3. :mod:`.noise_levels`: each pixel's own noise level, read from the last solve.
4. :mod:`.decision`: each pixel's distance against its level, with
   :mod:`.coherence` (the Potts field over the per-pixel rule) and
   :mod:`.photometric` (the lighting test: shadows and reflections dropped).
5. The blob rules, on one labelling (:mod:`.blobs`): :mod:`.ghost` (blobs where
   the background is wrong) and :mod:`.held_foreground` (blobs nothing moves in).
6. :mod:`.lines`: blobs that are lines, not bodies, left out of the published
   mask (the window still keeps them out).
7. :mod:`.holes`: outlines bridged over the field's neighbourhood, and what a
   body's outline encloses, alone or with one side of the frame, filled in the
   published mask (the window keeps the unfilled decision).
8. :mod:`.upsizing`: the mask at the camera's size.
9. :mod:`.background_memory`: the frame admitted to the window every few frames,
   its foreground replaced by the background (conditional update).

Apart from the frames, in the solve thread: :mod:`.window_solve` (a window
snapshot in, a background model out) and :mod:`.solve_resolution` (the solve
at a capped size, the full-size background carried from it).

Around them: :mod:`.contract` (:class:`StreamingDetector`, the contract every
detector the node and ``dgmod separate --mode stream`` run implements, and the
solve protocol), :mod:`.results` (what detectors hand out),
:mod:`.settings` (parameter checks, all-or-nothing reconfiguration) and
:mod:`.sliding_window` (:class:`SlidingWindowDetector`, which runs the
stages). The compiled passes sit apart in :mod:`.kernels`, one module per
stage they serve, each beside its numpy reference.

OpenCV's subtractors implement the same contract in
:class:`dgmod_ros.core.subtractors.OpenCVSubtractor`.
"""

from .contract import StreamingDetector
from .results import (BackgroundModel, FrameResult, SolveInFlight, SolverFailure, SolveTicket,
                      WindowSnapshot)
from .sliding_window import SlidingWindowDetector

__all__ = ['BackgroundModel', 'FrameResult', 'SlidingWindowDetector', 'SolveInFlight',
           'SolverFailure', 'SolveTicket', 'StreamingDetector', 'WindowSnapshot']
