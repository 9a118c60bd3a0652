# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
# Imported at module level: a missing linter is a failure, never a skip
# (ament_flake8 is pinned in requirements.txt).
from ament_flake8.main import main_with_errors
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = main_with_errors(argv=[])
    assert rc == 0, 'Found %d code style errors / warnings:\n' % len(errors) + '\n'.join(errors)
