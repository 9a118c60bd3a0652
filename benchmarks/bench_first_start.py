# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Time the detector's first start from a fresh home folder: first log line, first mask, Ctrl-C.

Each run starts the ``detector`` executable with ``HOME`` a new empty folder
and ``NUMBA_CACHE_DIR`` / ``XDG_CACHE_HOME`` unset (a user on whose machine
the detector never ran), while a camera in this process publishes 640 x 480
rgb8 at 30 frames/s from before the start (the package's Fast DDS profile on
both sides). Printed per run: seconds from the process's start to its first
log line, to the first mask received, and from SIGINT to the process's exit,
with its exit status and whether its output held a traceback.

Two installs: ``--build`` (default) runs ``colcon build`` into a temporary
workspace first and starts ``install/dgmod_ros/lib/dgmod_ros/detector`` (the
kernels compiled at install time); ``--executable PATH`` starts another one,
for example ``.venv/bin/detector`` of ``make test``'s editable install, which
has no install-time kernels (its first start compiles them in a child
process). ``--sigint-at S`` sends SIGINT S s after the start instead of after
the first mask (Ctrl-C while the kernels compile).

Usage (repo root): PYTHONPATH=. .venv/bin/python benchmarks/bench_first_start.py
    [--executable PATH] [--runs 1] [--sigint-at S] [--size 640x480]
"""

import argparse
import os
from pathlib import Path
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time

REPO = Path(__file__).resolve().parents[1]
PROFILE = REPO / 'config' / 'fastdds_large_images.xml'


def colcon_build(workspace):
    """Build the package with colcon into ``workspace``; return its detector and the seconds."""
    colcon = shutil.which('colcon') or str(Path(sys.executable).with_name('colcon'))
    start = time.monotonic()
    subprocess.run([colcon, '--log-base', str(workspace / 'log'), 'build', '--base-paths',
                    str(REPO), '--build-base', str(workspace / 'build'), '--install-base',
                    str(workspace / 'install')], check=True, capture_output=True, timeout=600)
    installed = workspace / 'install' / 'dgmod_ros' / 'lib' / 'dgmod_ros' / 'detector'
    return installed, time.monotonic() - start


def fresh_environment(executable, home, domain):
    """Return a new user's environment: empty ``home``, no cache settings, the profile."""
    env = {key: value for key, value in os.environ.items()
           if key not in ('NUMBA_CACHE_DIR', 'XDG_CACHE_HOME', 'PYTHONPATH')}
    env.update(HOME=str(home), ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED='1',
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE))
    install = Path(executable).resolve().parents[2]
    sites = list((install / 'lib').glob('python3*/site-packages'))
    if sites:       # a colcon install, as `source install/setup.bash` would set it
        env['PYTHONPATH'] = str(sites[0])
        env['AMENT_PREFIX_PATH'] = os.pathsep.join(
            [str(install), env.get('AMENT_PREFIX_PATH', '')])
    return env


def one_run(executable, size, sigint_at):
    """Start the detector once from a fresh home folder; return its figures."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import qos_profile_sensor_data, QoSProfile
    from sensor_msgs.msg import Image

    from dgmod_ros.core.synthetic import synthetic_scene
    from dgmod_ros.image_conversion import fill_image

    width, height = (int(v) for v in size.split('x'))
    messages = [fill_image(Image(), frame, 'rgb8')
                for frame in synthetic_scene(n_frames=30, shape=(height, width)).frames]
    domain = random.randint(120, 200)
    os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(PROFILE)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    home = Path(tempfile.mkdtemp(prefix='dgmod-home-'))
    figures = {}
    try:
        node = rclpy.create_node('bench_first_start', context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        masks = []
        node.create_subscription(Image, 'foreground_mask', masks.append, QoSProfile(depth=50))
        publisher = node.create_publisher(Image, 'image', qos_profile_sensor_data)
        started = time.monotonic()
        process = subprocess.Popen([str(executable)], env=fresh_environment(executable, home,
                                                                            domain),
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        os.set_blocking(process.stdout.fileno(), False)
        output, index, sent = b'', 0, None
        next_frame = time.monotonic()
        while process.poll() is None and time.monotonic() - started < 180:
            now = time.monotonic()
            if now >= next_frame:
                msg = messages[index % len(messages)]
                msg.header.stamp.sec = index // 30
                msg.header.stamp.nanosec = (index % 30) * 33_333_333
                publisher.publish(msg)
                index += 1
                next_frame += 1 / 30
            executor.spin_once(timeout_sec=max(0.0, min(0.01, next_frame - time.monotonic())))
            chunk = process.stdout.read()
            if chunk:
                output += chunk
                if 'first_log_s' not in figures and b'[' in output:
                    figures['first_log_s'] = time.monotonic() - started
                    figures['first_log'] = output.decode(errors='replace').splitlines()[0]
            if masks and 'first_mask_s' not in figures:
                figures['first_mask_s'] = time.monotonic() - started
            due = (sigint_at is not None and now - started >= sigint_at) or \
                (sigint_at is None and masks)
            if due and sent is None:
                process.send_signal(signal.SIGINT)
                sent = time.monotonic()
        if process.poll() is None:
            process.kill()
        process.wait()
        figures['stop_s'] = time.monotonic() - sent if sent is not None else float('nan')
        output += process.stdout.read() or b''
        text = output.decode(errors='replace')
        figures.update(returncode=process.returncode, traceback='Traceback' in text,
                       compiled='compiling kernels' in text, lines=text.splitlines())
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
        shutil.rmtree(home, ignore_errors=True)
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--executable', help='a detector to start (default: colcon build one)')
    parser.add_argument('--runs', type=int, default=1)
    parser.add_argument('--sigint-at', type=float, default=None,
                        help='send SIGINT this many s after the start '
                        '(default: after the first mask)')
    parser.add_argument('--size', default='640x480')
    args = parser.parse_args()
    workspace = None
    if args.executable is None:
        workspace = Path(tempfile.mkdtemp(prefix='dgmod-ws-'))
        executable, seconds = colcon_build(workspace)
        print(f'colcon build: {seconds:.1f} s (the kernels compiled at install time)')
    else:
        executable = Path(args.executable).absolute()
    try:
        for run in range(args.runs):
            figures = one_run(executable, args.size, args.sigint_at)
            nan = float('nan')
            print(f"run {run + 1}: first log line {figures.get('first_log_s', nan):.2f} s, "
                  f"first mask {figures.get('first_mask_s', nan):.2f} s, "
                  f"SIGINT to exit {figures['stop_s']:.2f} s, exit {figures['returncode']}, "
                  f"traceback {figures['traceback']}, compiled at start {figures['compiled']}")
            for line in figures['lines']:
                print('   ', line)
    finally:
        if workspace is not None:
            shutil.rmtree(workspace, ignore_errors=True)


if __name__ == '__main__':
    main()
