# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'dgmod_ros'

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
    entry_points={
        'console_scripts': [
            'detector = dgmod_ros.detector_node:main',
            'dgmod = dgmod_ros.cli:main',
        ],
    },
)
