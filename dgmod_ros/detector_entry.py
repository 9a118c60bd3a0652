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


_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class _Stop:
    """A stop signal's handler that also remembers it came: an import may swallow the interrupt."""

    def __init__(self):
        self.asked = False

    def __call__(self, signum, frame):
        self.asked = True
        raise KeyboardInterrupt


def main(args=None):
    """Run the detector (:func:`dgmod_ros.detector_node.main`), its kernels compiling first."""
    from rclpy.logging import get_logger

    from .core.kernel_cache import start_compile

    pending = None
    # Until rclpy.init installs its handlers, SIGINT and SIGTERM stop the
    # imports, so the child is ended too. Once in a clean-clone run a Ctrl-C
    # at the first line was lost and the detector started: an import may
    # swallow the KeyboardInterrupt (an optional module imported under a bare
    # ``except``). The handler remembers the signal; the stop then comes
    # after the import.
    stop = _Stop()
    previous = {number: signal.signal(number, stop) for number in _STOP_SIGNALS}
    try:
        pending = start_compile(get_logger('detector').info, say_ready=True)
        from .detector_node import main as run_node
    except KeyboardInterrupt:
        stop.asked = True
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    if not stop.asked:
        try:
            return run_node(args, kernel_compile=pending)
        except KeyboardInterrupt:       # before rclpy.init installed its handlers
            pass
    if pending is not None:
        pending.stop()
    return 0


if __name__ == '__main__':
    sys.exit(main())
