# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Dual-graph regularized moving-object detection for ROS 2 (numerical core in ``core``)."""
