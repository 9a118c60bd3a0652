# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    main = pytest.importorskip('ament_flake8.main')
    rc, errors = main.main_with_errors(argv=[])
    assert rc == 0, 'Found %d code style errors / warnings:\n' % len(errors) + '\n'.join(errors)
