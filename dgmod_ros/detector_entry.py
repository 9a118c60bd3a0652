# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The installed ``detector`` executable: says what it does before the node's imports.

Importing the node (numpy, SciPy, OpenCV, numba, the messages) takes 1-3 s
on two cores, and a cold kernel cache 30-60 s more. So this module imports
only rclpy's logging and :mod:`~dgmod_ros.core.kernel_cache` (no numba),
starts the kernel compile in a child process if the cache is not ready for
this install, logs that, and only then imports the node, which waits for the
child at configure (docs/node.md, "First start"). Ctrl-C or SIGTERM at any
moment ends the process and the child quietly.
"""

import signal
import sys


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def main(args=None):
    """Run the detector (:func:`dgmod_ros.detector_node.main`), its kernels compiling first."""
    from rclpy.logging import get_logger

    from .core.kernel_cache import start_compile

    pending = None
    # Until rclpy.init installs its handlers, SIGTERM stops the imports as
    # Ctrl-C does, so the child is ended too.
    previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        pending = start_compile(get_logger('detector').info, say_ready=True)
        from .detector_node import main as run_node
    except KeyboardInterrupt:
        if pending is not None:
            pending.stop()
        return 0
    finally:
        signal.signal(signal.SIGTERM, previous)
    return run_node(args, kernel_compile=pending)


if __name__ == '__main__':
    sys.exit(main())
