# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The benchmarks' scripts loaded as modules, for the tests of their functions."""

import importlib.util
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / 'benchmarks'


def load(name):
    """Return the module of ``benchmarks/<name>.py``, executed once per call."""
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f'{name}.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
