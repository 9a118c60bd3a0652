# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from glob import glob
import os

from setuptools import Command, find_packages, setup
from setuptools.command.install import install

package_name = 'dgmod_ros'


class install_kernels(Command):
    """
    Compile the numba kernels against the files just installed (``colcon build``).

    numba keys a cached kernel by its source file's path and mtime, so the
    kernels are compiled after the install, from the installed files, into
    ``dgmod_ros/kernel_seed/`` beside them; the first start copies them into
    the user's cache (``dgmod_ros/core/kernel_cache.py``, docs/node.md "First
    start"). Skipped for a staged install (``--root``: a wheel, a Debian
    package), whose paths are not the final ones, and with
    ``DGMOD_SKIP_KERNEL_COMPILE=1``. A failure is reported and not fatal:
    the first start then compiles in a child process.
    """

    description = "compile the installed package's numba kernels into its kernel seed"
    user_options = []

    def initialize_options(self):
        self.install_dir = None
        self.root = None
        self.outputs = []

    def finalize_options(self):
        self.set_undefined_options('install', ('install_lib', 'install_dir'), ('root', 'root'))

    def run(self):
        import subprocess
        import sys
        import time
        if self.root or os.environ.get('DGMOD_SKIP_KERNEL_COMPILE'):
            print('install_kernels: skipped (staged install or DGMOD_SKIP_KERNEL_COMPILE); '
                  'the first start compiles them')
            return
        library = os.path.abspath(self.install_dir)
        seed = os.path.join(library, package_name, 'kernel_seed')
        code = ('import sys; sys.path.insert(0, {!r}); '
                'from dgmod_ros.core.warmup import main; sys.exit(main())').format(library)
        print(f'install_kernels: compiling the kernels into {seed} (30-60 s on two cores)')
        start = time.monotonic()
        done = subprocess.run([sys.executable, '-P', '-c', code],
                              env=dict(os.environ, NUMBA_CACHE_DIR=seed),
                              capture_output=True, text=True)
        if done.returncode != 0:
            print('install_kernels: compile failed, the first start compiles them:\n'
                  + (done.stdout + done.stderr)[-2000:])
            return
        print(f'install_kernels: done in {time.monotonic() - start:.0f} s')
        self.outputs = [os.path.join(folder, name)
                        for folder, _, names in os.walk(seed) for name in names]

    def get_outputs(self):
        return self.outputs


class install_with_kernels(install):
    """``setup.py install`` (what colcon runs), then :class:`install_kernels`."""

    sub_commands = install.sub_commands + [('install_kernels', None)]


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'benchmarks']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        (os.path.join('share', package_name, 'config'),
         glob('config/*.yaml') + glob('config/*.xml')),
        (os.path.join('share', package_name, 'launch'), glob('launch/*.launch.xml')),
    ],
    # What the code imports at run time, besides ROS 2 (rclpy and the message
    # packages come from a ROS install, or from the ros-jazzy-* wheels that
    # requirements.txt pins; they are declared in package.xml). rosbags is for
    # the offline command's rosbag2 input.
    install_requires=['setuptools', 'numpy', 'scipy', 'opencv-python-headless', 'PyYAML',
                      'numba', 'rosbags'],
    zip_safe=True,
    maintainer='dgmod_ros maintainers',
    maintainer_email='maintainers@dgmod-ros.invalid',
    description='Dual-graph regularized moving-object detection for ROS 2',
    license='Apache-2.0',
    extras_require={'test': ['pytest']},
    cmdclass={'install': install_with_kernels, 'install_kernels': install_kernels},
    entry_points={
        'console_scripts': [
            'detector = dgmod_ros.detector_entry:main',
            'dgmod = dgmod_ros.cli:main',
        ],
    },
)
