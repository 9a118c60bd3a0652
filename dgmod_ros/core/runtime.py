# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""Process-wide settings that make the solvers fast on small machines."""

import ctypes
import ctypes.util
import os
import sys
import threading

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_applied = False
# ((modules imported, count), libraries limited) of the last limit_blas_threads.
_limited = None


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


# Nice increment of a helper thread that decodes or encodes files: the same
# weight against the separation's threads as a process at nice 10 (about a
# tenth of the CPU when both want it).
IO_THREAD_NICENESS = 10


def yield_to_compute(increment=IO_THREAD_NICENESS):
    """
    Lower the calling thread's scheduling priority by ``increment`` (Linux only).

    ``dgmod separate`` decodes frames and encodes masks in helper threads
    with queues of slack. On two cores the window solve is the critical
    path, and every time slice a helper takes from it delays the stream
    (docs/node.md, "less memory traffic"); with this, the helpers run when the
    separation's threads wait. On Linux the nice value is a per-thread
    attribute, so only the caller changes; elsewhere it would be the whole
    process, so nothing is done. Returns True where the priority changed.
    """
    if not sys.platform.startswith('linux') or not hasattr(os, 'setpriority'):
        return False
    thread = threading.get_native_id()
    try:
        os.setpriority(os.PRIO_PROCESS, thread, os.getpriority(os.PRIO_PROCESS, thread)
                       + int(increment))
    except OSError:
        return False
    return True


_OPENBLAS_SETTERS = ('openblas_set_num_threads', 'openblas_set_num_threads64_',
                     'scipy_openblas_set_num_threads', 'scipy_openblas_set_num_threads64_')


def limit_blas_threads(count=1):
    """
    Set the thread count of every OpenBLAS loaded in this process (numpy's, scipy's).

    The fused solver kernels run on numba's thread pool; OpenBLAS's own
    threads, busy-waiting beside them between the sweep's small products,
    made a sweep several times slower on the loaded two-core machine
    (docs/solver.md). With the kernels owning the cores, the products are
    cheaper single-threaded. Returns how many libraries took the setting
    (0 where no OpenBLAS is loaded, for example a reference BLAS).

    The loaded libraries are read from ``/proc/self/maps`` again only when
    modules were imported since the last call with the same ``count``: a
    new OpenBLAS comes with an extension module's import, and the read
    (1-2 ms) ran before every channel's fit.
    """
    global _limited
    key = (len(sys.modules), int(count))
    if _limited is not None and _limited[0] == key:
        return _limited[1]
    try:
        with open('/proc/self/maps') as maps:
            # Only the few lines that name an OpenBLAS are split: splitting
            # all of them took most of the call's milliseconds (it runs
            # before every fused solve).
            fields = [line.split() for line in maps if 'openblas' in line.lower()]
    except OSError:
        return 0
    paths = {f[-1] for f in fields
             if len(f) == 6 and 'openblas' in f[-1].rsplit('/', 1)[-1].lower()
             and '.so' in f[-1]}
    limited = 0
    for path in sorted(paths):
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for name in _OPENBLAS_SETTERS:
            setter = getattr(library, name, None)
            if setter is not None:
                setter(int(count))
                limited += 1
                break
    _limited = (key, limited)
    return limited
