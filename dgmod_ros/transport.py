# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The large-image transport advice the node gives once (no ROS import needed)."""

import os
from pathlib import Path
import threading

PROFILE_NAME = 'fastdds_large_images.xml'
PROFILE_VARIABLE = 'FASTRTPS_DEFAULT_PROFILES_FILE'
# Fast DDS's default shared-memory segment per participant.
DEFAULT_SEGMENT_BYTES = 512 * 1024


def profile_path():
    """
    Return the path of the package's Fast DDS profile for large images.

    The installed copy (``share/dgmod_ros/config``, found through
    ``ament_index_python``) where the package is installed, else the copy in
    this source tree.
    """
    try:
        from ament_index_python.packages import get_package_share_directory
        installed = Path(get_package_share_directory('dgmod_ros')) / 'config' / PROFILE_NAME
        if installed.is_file():
            return installed
    except (ImportError, LookupError, OSError, ValueError):  # not installed, no AMENT_PREFIX_PATH
        pass
    return Path(__file__).resolve().parents[1] / 'config' / PROFILE_NAME


class LargeImageCheck:
    """
    Warn once when images exceed Fast DDS's default shared-memory segment and no profile is set.

    Images over 512 KB published from another process mostly do not arrive
    through the default segment (docs/node.md, "Transport"); the fix is a
    profile set for the camera driver and the node.

    Parameters
    ----------
    environ : mapping, default=os.environ
        Where ``FASTRTPS_DEFAULT_PROFILES_FILE`` is looked up.

    """

    def __init__(self, environ=None):
        self.environ = os.environ if environ is None else environ
        self.warned_ = False
        self._lock = threading.Lock()

    def check(self, size_bytes, what=None):
        """
        Return the warning text the first time a large image arrives unprofiled, else None.

        ``what`` names the payload in the warning (default: images of
        ``size_bytes`` bytes), for a colour frame and its depth partner.
        """
        if self.warned_ or size_bytes <= DEFAULT_SEGMENT_BYTES \
                or self.environ.get(PROFILE_VARIABLE):
            return None
        with self._lock:
            if self.warned_:
                return None
            self.warned_ = True
        what = what or f'images of {size_bytes} bytes'
        return (f'{what} exceed the default Fast DDS '
                f'{DEFAULT_SEGMENT_BYTES} byte shared-memory segment and '
                f'{PROFILE_VARIABLE} is not set: frames from another process will be '
                f'lost. Set {PROFILE_VARIABLE}={profile_path()} for the camera driver '
                f'and this node (docs/node.md, "Transport").')
