# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""colcon builds the package; the installed detector runs as ``ros2 run`` would start it."""

import os
from pathlib import Path
import random
import shutil
import signal
import subprocess
import sys
import time

from dgmod_ros.core.synthetic import synthetic_scene
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile
from ros_harness import image_message
from sensor_msgs.msg import Image

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def install(tmp_path_factory):
    colcon = shutil.which('colcon') or str(Path(sys.executable).with_name('colcon'))
    if not Path(colcon).exists():
        pytest.skip('colcon is not installed')
    workspace = tmp_path_factory.mktemp('ws')
    # Build outside the repository: ament_flake8 would lint an in-repo install/.
    result = subprocess.run(
        [colcon, '--log-base', str(workspace / 'log'), 'build', '--base-paths', str(REPO),
         '--build-base', str(workspace / 'build'), '--install-base', str(workspace / 'install')],
        capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    return workspace / 'install' / 'dgmod_ros'


def test_installed_layout(install):
    for script in ('detector', 'dgmod'):
        path = install / 'lib' / 'dgmod_ros' / script        # where `ros2 run` looks
        assert path.is_file() and os.access(path, os.X_OK)
    share = install / 'share'
    assert (share / 'dgmod_ros' / 'config' / 'detector.yaml').is_file()
    assert (share / 'dgmod_ros' / 'launch' / 'detector.launch.xml').is_file()
    assert (share / 'dgmod_ros' / 'config' / 'fastdds_large_images.xml').is_file()
    assert (share / 'dgmod_ros' / 'package.xml').is_file()
    assert (share / 'ament_index' / 'resource_index' / 'packages' / 'dgmod_ros').is_file()


def _environment(install, domain):
    env = dict(os.environ)
    site = next((install / 'lib').glob('python3*/site-packages'))
    env['PYTHONPATH'] = os.pathsep.join([str(site), env.get('PYTHONPATH', '')])
    env['AMENT_PREFIX_PATH'] = os.pathsep.join([str(install), env.get('AMENT_PREFIX_PATH', '')])
    env['ROS_DOMAIN_ID'] = str(domain)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['PYTHONUNBUFFERED'] = '1'
    return env


def _start(install, domain):
    params = install / 'share' / 'dgmod_ros' / 'config' / 'detector.yaml'
    return subprocess.Popen(
        [str(install / 'lib' / 'dgmod_ros' / 'detector'), '--ros-args', '--params-file',
         str(params), '-p', 'window:=10', '-p', 'stride:=5'],
        env=_environment(install, domain), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True)


@pytest.mark.parametrize('stop_signal', [signal.SIGINT, signal.SIGTERM])
def test_installed_detector_masks_frames_and_stops_cleanly(install, monkeypatch, stop_signal):
    domain = random.randint(120, 200)          # away from other tests' traffic
    process = _start(install, domain)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    try:
        node = rclpy.create_node('build_test_client', context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        masks = []
        node.create_subscription(Image, 'foreground_mask', masks.append, QoSProfile(depth=50))
        publisher = node.create_publisher(Image, 'image', QoSProfile(depth=10))
        frames = synthetic_scene(n_frames=20, shape=(48, 64)).frames
        # The install compiled the kernels (numba's cache is per installed
        # file); a slow machine may still take a while to load them.
        deadline = time.monotonic() + 90
        index = 0
        while len(masks) < 3 and time.monotonic() < deadline:
            assert process.poll() is None, process.communicate()[0]
            if publisher.get_subscription_count():
                publisher.publish(image_message(frames[index % 20], 'rgb8', index))
                index += 1
            executor.spin_once(timeout_sec=0.1)
        assert len(masks) >= 3, 'the installed detector published no masks'
        assert masks[0].width == 64 and masks[0].height == 48
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
        process.send_signal(stop_signal)
        # A hang fails here; how fast it stops is a figure, not a test.
        output, _ = process.communicate(timeout=10)
    assert 'detector ready' in output
    assert process.returncode == 0, output
    assert 'Traceback' not in output, output


def test_the_install_compiled_the_kernels_and_a_fresh_home_loads_them(install, tmp_path):
    from dgmod_ros.core import kernel_cache
    package = next((install / 'lib').glob('python3*/site-packages')) / 'dgmod_ros'
    seed = package / kernel_cache.SEED_NAME
    assert kernel_cache.is_ready(seed, package)           # for the installed files
    assert list(seed.rglob('*.nbi')) and list(seed.rglob('*.nbc'))
    # A new user: empty home, no cache setting. The detector copies the seed
    # and loads it; nothing is compiled at start-up.
    env = _environment(install, random.randint(120, 200))
    env.pop('NUMBA_CACHE_DIR', None)
    env.pop('XDG_CACHE_HOME', None)
    env['HOME'] = str(tmp_path)
    process = subprocess.Popen([str(install / 'lib' / 'dgmod_ros' / 'detector')], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines = []
    try:
        for line in process.stdout:
            lines.append(line)
            if 'detector ready' in line:
                break
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    output = ''.join(lines) + output
    assert 'loading them from ' + str(tmp_path / '.cache' / 'dgmod_ros' / 'numba') in lines[0]
    assert 'detector ready' in output and 'compiling kernels' not in output, output
    assert kernel_cache.is_ready(tmp_path / '.cache' / 'dgmod_ros' / 'numba', package)
    assert process.returncode == 0 and 'Traceback' not in output, output
