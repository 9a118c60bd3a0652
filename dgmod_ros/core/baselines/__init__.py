# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Comparison methods, one class each, with the ``fit(data, frame_shape, init=None)`` interface."""
