# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
``package.xml`` is a valid format 3 manifest that agrees with ``setup.py``.

Checked with catkin_pkg, the parser colcon and bloom read manifests with: it
refuses unknown elements and attributes and checks names, versions, licenses,
maintainers and dependencies against REP 149 (format 3). ament_xmllint's XML
Schema check needs the schema from the ROS web site, which a test here cannot
download.
"""

from pathlib import Path
import re

from catkin_pkg.package import parse_package
import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.linter
def test_package_xml_is_a_valid_format_3_manifest():
    warnings = []
    package = parse_package(str(REPO / 'package.xml'), warnings=warnings)
    assert not warnings, warnings
    assert package.package_format == 3
    assert package.name == 'dgmod_ros'
    assert package.get_build_type() == 'ament_python'
    assert package.licenses == ['Apache-2.0']
    setup = (REPO / 'setup.py').read_text(encoding='utf-8')
    assert re.search(rf"version='{re.escape(package.version)}'", setup)
    assert 'package_format3.xsd' in (REPO / 'package.xml').read_text(encoding='utf-8')


@pytest.mark.linter
def test_an_invalid_manifest_is_refused(tmp_path):
    text = (REPO / 'package.xml').read_text(encoding='utf-8')
    broken = tmp_path / 'package.xml'
    broken.write_text(text.replace('<license>', '<licence>').replace('</license>',
                                                                     '</licence>'))
    with pytest.raises(Exception, match='licen'):
        parse_package(str(broken))
