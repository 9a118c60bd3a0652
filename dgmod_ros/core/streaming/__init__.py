# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Streaming detection: a mask for every frame, window solves apart from the frames.

Modules, one job each:

- :mod:`.contract`: :class:`StreamingDetector`, the contract every detector the
  node and ``dgmod separate --mode stream`` run implements, and the solve
  protocol (tickets that tie a solve to the detector and configuration that
  started it).
- :mod:`.results`: what detectors hand out (:class:`FrameResult`,
  :class:`WindowSnapshot`, :class:`BackgroundModel`, :class:`SolverFailure`).
- :mod:`.settings`: parameter checks and all-or-nothing reconfiguration.
- :mod:`.buffer`: the buffered frames of a window, their rescaling, and the
  scene-change rule that restarts the window.
- :mod:`.background_memory`: the window's columns, admitted every few frames
  with their foreground replaced by the background (conditional update).
- :mod:`.fast_path`: a frame's background from the last solve (l1 projection by IRLS).
- :mod:`.foreground`: the decision: each pixel against its own noise level, the ghost test.
- :mod:`.photometric`: the lighting test of the decision (brightness ratio,
  chromaticity), which drops shadows and reflections.
- :mod:`.texture`: the LBSP descriptor distance between a frame and its background.
- :mod:`.window_solve`: one window solve, snapshot in, background model out.
- :mod:`.sliding_window`: :class:`SlidingWindowDetector`, which puts them together.

OpenCV's subtractors implement the same contract in
:class:`dgmod_ros.core.subtractors.OpenCVSubtractor`.
"""

from .contract import StreamingDetector
from .results import (BackgroundModel, FrameResult, SolveInFlight, SolverFailure, SolveTicket,
                      WindowSnapshot)
from .sliding_window import SlidingWindowDetector

__all__ = ['BackgroundModel', 'FrameResult', 'SlidingWindowDetector', 'SolveInFlight',
           'SolverFailure', 'SolveTicket', 'StreamingDetector', 'WindowSnapshot']
