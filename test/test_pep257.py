# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
# Imported at module level: a missing linter is a failure, never a skip
# (ament_pep257 is pinned in requirements.txt).
from ament_pep257.main import main
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'
