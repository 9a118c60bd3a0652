# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Shared fixtures: where the real sequences live, and a quiet ROS set-up."""

import multiprocessing
import os
from pathlib import Path

import pytest

# In-process ROS tests must not see other processes' nodes (and vice versa);
# rclpy reads this at init, so it is set before any test creates a context.
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'OFF')

# flake8 lints in a process pool. Forked from a test process whose ROS (DDS)
# threads ran, its workers crashed (segmentation fault in tokenize) and the pool
# hung; fresh interpreters do not inherit that state.
multiprocessing.set_start_method('forkserver', force=True)

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get('DGMOD_DATA', REPO.parent / 'shared' / 'data'))


@pytest.fixture(scope='session')
def data_dir():
    """Locate the shared real sequences (../shared/data); skip when absent."""
    if not (DATA / 'sbi_IBMtest2' / 'input').is_dir():
        pytest.skip(f'real sequences not found under {DATA}')
    return DATA
