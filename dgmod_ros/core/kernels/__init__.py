# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The core's compiled passes, one module per module they serve.

``kernels/dgmod.py`` holds the fused ADMM sweep of
:class:`~dgmod_ros.core.dgmod.DualGraphMOD` (and the Gram matrix
:func:`~dgmod_ros.core.linalg.gram_matrix` hands it), ``graphs.py`` the
spatial graph's sums, ``preprocess.py`` the half-size frame conversion and
``depth_background.py`` the depth background's update. Each imports
:mod:`~dgmod_ros.core.numba_setup` only; the modules they serve import them
when first called, so a process that never runs a pass never loads numba.
"""
