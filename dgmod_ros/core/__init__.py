# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The ROS-free numerical core: models, graphs, baselines, masks, metrics, streaming."""
