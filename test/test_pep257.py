# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
import pytest


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    main = pytest.importorskip('ament_pep257.main')
    rc = main.main(argv=['.', 'test'])
    assert rc == 0, 'Found code style errors / warnings'
