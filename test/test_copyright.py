# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
HEADER = ['# Copyright 2026 dgmod_ros authors', '# Licensed under the Apache License, Version 2.0']


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    # ament_copyright is not on PyPI; on a ROS install from apt it runs. The
    # header test below runs everywhere.
    main = pytest.importorskip('ament_copyright.main')
    rc = main.main(argv=['.', 'test'])
    assert rc == 0, 'Found errors'


@pytest.mark.copyright
@pytest.mark.linter
def test_every_python_file_starts_with_the_header():
    files = [p for p in REPO.rglob('*.py')
             if not {'.venv', 'build', 'install', 'log', 'out'} & set(p.relative_to(REPO).parts)]
    assert len(files) > 30
    missing = [str(p.relative_to(REPO)) for p in files
               if p.read_text(encoding='utf-8').splitlines()[:2] != HEADER]
    assert not missing, 'files without the two-line header: ' + ', '.join(missing)
