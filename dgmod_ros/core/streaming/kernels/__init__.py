# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The per-frame path's and the window solve's compiled passes, one module per stage they serve.

Each module is named after the stage module of :mod:`dgmod_ros.core.streaming`
whose work it compiles (``kernels/coherence.py`` serves ``coherence.py``) and
holds the passes' numpy references and their registrations
(:func:`~dgmod_ros.core.numba_setup.register_pass`). They import
:mod:`~dgmod_ros.core.numba_setup` and one another, never a stage: the stages
import them. :mod:`.texture`, the LBSP descriptor, serves the decision's
moving-texture rule and the lighting test.
"""
