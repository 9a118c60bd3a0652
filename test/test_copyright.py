# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
import pytest


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    # ament_copyright is not on PyPI; on a ROS install from apt it runs.
    main = pytest.importorskip('ament_copyright.main')
    rc = main.main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'
