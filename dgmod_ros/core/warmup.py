# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Compile (or load from the cache) every compiled pass of the package before it is needed.

A cold compile takes tens of seconds on a small machine and holds the GIL,
and a pass compiled on its first call stalls the caller (the node's image
callback) for 50-250 ms. :func:`compile_all` imports every module of the
``kernels`` subpackages (``dgmod_ros/core/kernels/``,
``dgmod_ros/core/streaming/kernels/``), each of which registers its passes
(:func:`~dgmod_ros.core.numba_setup.register_pass`), and warms every
registered pass up on its examples: no list of passes to keep in step here.

This module sits above every pass; only the entry points import it (the
node's configure step through :func:`dgmod_ros.config.load_kernels`,
``python3 -m dgmod_ros.core.warmup``; ``test/test_import_graph.py`` holds
that). ``colcon build`` runs :func:`main` at install time, and a process
that finds the cache cold runs it in a child
(:class:`~dgmod_ros.core.kernel_cache.ChildCompile`), then loads.
"""

import importlib
import pkgutil
import signal
import sys
import time

from . import numba_setup
from .kernel_cache import mark_ready

PACKAGE = __package__.split('.')[0]


def kernel_modules():
    """Return the names of every module of the package's ``kernels`` subpackages."""
    core = importlib.import_module(__package__)
    names = []
    for info in pkgutil.walk_packages(core.__path__, __package__ + '.'):
        if info.ispkg and info.name.rpartition('.')[2] == 'kernels':
            package = importlib.import_module(info.name)
            names += [f'{info.name}.{module.name}'
                      for module in pkgutil.iter_modules(package.__path__)]
    return sorted(names)


def compile_all():
    """
    Compile (or load from the cache) every registered pass on its examples.

    At the end the cache is marked ready for this install, with the
    compile's seconds where anything was compiled.
    """
    start = time.monotonic()
    for name in kernel_modules():
        importlib.import_module(name)
    for compiled_pass in numba_setup.PASSES:
        compiled_pass.warm_up()
    compiled = any(sum(dispatcher.stats.cache_misses.values()) for dispatcher in _dispatchers())
    mark_ready(time.monotonic() - start if compiled else None)


def _dispatchers():
    from numba.core.registry import CPUDispatcher
    return [value for name, module in list(sys.modules.items())
            if name.startswith(PACKAGE) and module is not None
            for value in vars(module).values() if isinstance(value, CPUDispatcher)]


def main():
    """
    Compile (or load) every pass into the cache, then mark it ready.

    ``python3 -m dgmod_ros.core.warmup`` does it ahead of a first start;
    ``setup.py``'s ``install_kernels`` runs it on the installed files.
    Returns the exit status (130 after Ctrl-C, which a cold compile may take
    seconds to notice).
    """
    try:
        compile_all()
    except KeyboardInterrupt:
        return 130
    return 0


def child_main():
    """Run :func:`main` as :class:`ChildCompile`'s child: SIGINT is its caller's to handle."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.exit(main())


if __name__ == '__main__':
    sys.exit(main())
