# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""package.xml, setup.py and the launch file agree with the code; bad start-up parameters."""

import ast
import os
from pathlib import Path
import re
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

from dgmod_ros import config
import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGE = REPO / 'dgmod_ros'

# Python module -> (rosdep key in package.xml, PyPI name in setup.py or None for ROS).
# ROS packages are their own rosdep keys and come from ROS, not from install_requires.
THIRD_PARTY = {
    'numpy': ('python3-numpy', 'numpy'),
    'scipy': ('python3-scipy', 'scipy'),
    'cv2': ('python3-opencv', 'opencv-python-headless'),
    'yaml': ('python3-yaml', 'PyYAML'),
    'numba': ('python3-numba', 'numba'),
    # Offline rosbag2 input only; no rosdep key verified (package.xml says so).
    'rosbags': (None, 'rosbags'),
}
ROS = {'rclpy', 'rcl_interfaces', 'sensor_msgs', 'std_msgs', 'std_srvs', 'diagnostic_msgs',
       'lifecycle_msgs', 'builtin_interfaces', 'ament_index_python'}


def _runtime_imports():
    modules = set()
    for path in PACKAGE.rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                modules.update(alias.name.split('.')[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                modules.add(node.module.split('.')[0])
    return modules - set(sys.stdlib_module_names) - {'dgmod_ros'}


def _package_xml():
    return ElementTree.parse(REPO / 'package.xml').getroot()


def _setup_call():
    tree = ast.parse((REPO / 'setup.py').read_text())
    return next(node for node in ast.walk(tree) if isinstance(node, ast.Call)
                and getattr(node.func, 'id', '') == 'setup')


def _setup_keyword(name):
    call = _setup_call()
    return next(k.value for k in call.keywords if k.arg == name)


def test_every_runtime_import_is_declared_in_package_xml_and_setup_py():
    imports = _runtime_imports()
    unknown = imports - set(THIRD_PARTY) - ROS
    assert not unknown, f'add {sorted(unknown)} to THIRD_PARTY or ROS here, and declare them'
    root = _package_xml()
    declared = {e.text for e in root if e.tag in ('exec_depend', 'depend')}
    install_requires = set(ast.literal_eval(_setup_keyword('install_requires')))
    requirements = (REPO / 'requirements.txt').read_text().lower()
    for module in sorted(imports):
        key, pypi = THIRD_PARTY.get(module, (module, None))
        if key is not None:
            assert key in declared, f'package.xml lacks <exec_depend>{key}</exec_depend>'
        else:
            assert module in (REPO / 'package.xml').read_text(), module   # explained there
        if pypi is not None:
            assert pypi in install_requires, f'setup.py install_requires lacks {pypi}'
            assert re.search(rf'^{re.escape(pypi.lower())}==', requirements, re.M), \
                f'requirements.txt does not pin {pypi}'
    assert not install_requires & ROS, 'ROS packages come from ROS, not from PyPI'


def test_launch_file_refers_only_to_names_that_exist():
    launch = ElementTree.parse(REPO / 'launch' / 'detector.launch.xml').getroot()
    args = {arg.get('name'): arg.get('default') for arg in launch.iter('arg')}
    text = (REPO / 'launch' / 'detector.launch.xml').read_text()
    used = set(re.findall(r'\$\(var (\w+)\)', text))
    assert used <= set(args), f'undeclared launch arguments: {used - set(args)}'
    package = _package_xml().find('name').text
    scripts = ast.literal_eval(_setup_keyword('entry_points'))['console_scripts']
    executables = {line.split('=')[0].strip() for line in scripts}
    nodes = list(launch.iter('node'))
    assert nodes
    for node in nodes:
        assert node.get('pkg') == package
        assert node.get('exec') in executables
        for param in node.iter('param'):
            if param.get('from') is not None:
                path = args[re.fullmatch(r'\$\(var (\w+)\)', param.get('from')).group(1)]
                share = f'$(find-pkg-share {package})/'
                assert path.startswith(share), path
                relative = path[len(share):]
                assert (REPO / relative).is_file(), relative
                assert config.load_parameter_file(REPO / relative) == {
                    spec.name: spec.default for spec in config.reads(config.NODE)}
            else:
                name = param.get('name')
                assert name in config.BY_NAME, f'no parameter {name}'
                value = args[re.fullmatch(r'\$\(var (\w+)\)', param.get('value')).group(1)]
                assert value == config._yaml_scalar(config.DEFAULTS[name]), name
        remapped = {remap.get('from') for remap in node.iter('remap')}
        assert remapped == set(SUBSCRIBED_TOPICS)
    # setup.py installs the launch and config folders into the package's share.
    data_files = ast.unparse(_setup_keyword('data_files'))
    assert "'launch/*.launch.xml'" in data_files and "'config/*.yaml'" in data_files


#: The topics the node can subscribe (checked against a running node in
#: test_depth_node.py): what a launch file may remap.
SUBSCRIBED_TOPICS = ('image', 'image/compressed', 'depth/image_rect', 'depth/camera_info')


def _run_detector(tmp_path, *ros_args):
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='OFF', PYTHONUNBUFFERED='1')
    return subprocess.run([sys.executable, '-m', 'dgmod_ros.detector_node', '--ros-args',
                           *ros_args], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=60)


@pytest.mark.parametrize('ros_args, names', [
    (['-p', 'stride:=99'], ['stride']),                 # cross-field rule: stride > window
    (['-p', 'window:=1000'], ['window', 'range']),      # out of range
    (['-p', 'lambda2:=1'], ['lambda2', 'DOUBLE']),      # wrong type
    ('yaml', ['method', 'pca']),                        # bad value in the YAML file
])
def test_bad_parameter_at_start_up_is_one_error_and_a_non_zero_exit(tmp_path, ros_args, names):
    if ros_args == 'yaml':
        params = tmp_path / 'bad.yaml'
        params.write_text('/detector:\n  ros__parameters:\n    method: pca\n')
        ros_args = ['--params-file', str(params)]
    result = _run_detector(tmp_path, *ros_args)
    output = result.stdout + result.stderr
    assert result.returncode == 1, output
    assert 'Traceback' not in output, output
    errors = [line for line in output.splitlines() if '[ERROR]' in line]
    assert len(errors) == 1, output
    assert all(name in errors[0] for name in names), errors[0]
