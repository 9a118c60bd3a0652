# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Process-wide settings that make the solvers fast on small machines."""

import ctypes
import ctypes.util

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_applied = False


def keep_freed_memory():
    """
    Ask glibc to recycle freed arrays instead of returning them to the OS.

    By default glibc serves every allocation above 128 KiB with a fresh
    ``mmap`` and unmaps it on free, so each n x m temporary of an ADMM sweep
    pays a page fault per 4 KiB on first touch (``docs/solver.md`` has the
    measured cost). Raising the
    mmap and trim thresholds keeps such blocks in the heap for reuse; resident
    memory then stays at the peak working set, which a long-running node
    reaches anyway. Call once at program start (the command line, the node
    and the benchmarks do). Returns True where it took effect (glibc only).
    """
    global _applied
    if _applied:
        return True
    name = ctypes.util.find_library('c')
    if name is None:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    # 32 MiB is glibc's largest accepted mmap threshold on 64-bit systems.
    ok = mallopt(_M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1
    ok = mallopt(_M_TRIM_THRESHOLD, 1024 * 1024 * 1024) == 1 and ok
    _applied = ok
    return ok
