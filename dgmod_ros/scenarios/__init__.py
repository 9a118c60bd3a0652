# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Synthetic scenarios with exact ground truth, built from the shared real sequences.

People cut out of the dev clips with their ground-truth masks, pasted with
soft edges onto the clips' clean backgrounds and scripted (in view from the
first frame, stopping for a minute, close to the camera, crossing), under
sensor noise and a slight light flicker. Nothing of the data is stored: the
suite is rebuilt from ``../shared/data`` and a seed. No ROS import.

``python -m dgmod_ros.scenarios --out out/scenarios --seed 0`` writes the
suite in the data's CDnet layout; :func:`build_suite` returns it in memory.
"""

from .compose import Scenario, truth_from_alpha
from .layout import describe, write_sequence
from .material import load_material
from .suite import build_scenario, build_suite, FPS, SCENARIO_NAMES

__all__ = ['Scenario', 'truth_from_alpha', 'describe', 'write_sequence', 'load_material',
           'build_scenario', 'build_suite', 'FPS', 'SCENARIO_NAMES']
