# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
The compiled passes' leaf: numba's process-wide settings, and what every pass shares.

Every module of compiled passes (``dgmod_ros/core/kernels/``,
``dgmod_ros/core/streaming/kernels/``) takes ``njit`` and ``prange`` from
here, so importing one always makes these settings first; this module
imports nothing of the package but :mod:`~dgmod_ros.core.kernel_cache` and
:mod:`~dgmod_ros.core.runtime`, neither of which loads numba.

Import side effects, all process-wide and made before the first compiled call:

- ``NUMBA_CACHE_DIR`` defaults to ``$XDG_CACHE_HOME/dgmod_ros/numba`` (else
  ``~/.cache/dgmod_ros/numba``) when unset, so an installed package in a
  read-only prefix still loads its compiled kernels from disk instead of
  compiling them at every start; the kernels an install compiled (colcon
  build) are copied there first where missing
  (:mod:`~dgmod_ros.core.kernel_cache`);
- ``numba.config.THREADING_LAYER = 'threadsafe'``: the node calls kernels from
  its image callback and its solve thread at once, and numba's ``workqueue``
  fallback stops the process when two threads enter it. ``threadsafe`` makes
  numba take ``tbb`` or ``omp`` (libgomp, which comes with gcc) or fail loudly;
- OpenBLAS runs on one thread (:func:`~dgmod_ros.core.runtime.limit_blas_threads`):
  the kernels own the cores, and OpenBLAS threads spinning beside them made a
  sweep several times slower (docs/solver.md, "Fused sweep").

The convention every pass follows (docs/solver.md, "Compiled passes"): a
pass sits in the kernel module named after the module it serves, beside its
numpy reference, and registers itself with :func:`register_pass`: the
examples it is warmed up on (:func:`~dgmod_ros.core.warmup.compile_all`)
are the ones ``test/test_compiled_passes.py`` checks it on against the reference.
"""

from dataclasses import dataclass
import os
from typing import Callable

from .kernel_cache import default_cache_dir, seed_cache

if not os.environ.get('NUMBA_CACHE_DIR'):
    os.environ['NUMBA_CACHE_DIR'] = default_cache_dir()
seed_cache()
# Also in the environment: numba re-reads its whole configuration from the
# environment when that changed since its import (the line above does, when
# another module imported numba first), which would reset an attribute set alone.
os.environ.setdefault('NUMBA_THREADING_LAYER', 'threadsafe')

import numba  # noqa: E402, I100 (the cache folder must be set before numba reads its config)
from numba import njit, prange  # noqa: E402, F401 (the passes' decorators, after the settings)
from numba.typed import List  # noqa: E402
import numpy as np  # noqa: E402

from .runtime import limit_blas_threads  # noqa: E402

if not numba.config.CACHE_DIR:      # numba was imported before this module
    numba.config.CACHE_DIR = os.environ['NUMBA_CACHE_DIR']
numba.config.THREADING_LAYER = 'threadsafe'
limit_blas_threads(1)

#: Pixels per block of the threaded loops: long enough rows for the vector
#: loops, blocks few enough per thread to amortise the per-block scratch
#: rows, many enough (75 at 320 x 240) to balance two to eight threads.
BLOCK_PIXELS = 1024

#: The passes' ``fastmath`` flags. Reassociation lets the compiler vectorise
#: the sums; no 'nnan'/'ninf': the solver detects a non-finite iterate from
#: its sums, and a non-finite frame must stay visible.
FAST_MATH = {'reassoc', 'contract', 'nsz'}


def use_threads(count):
    """
    Let the kernels that the calling thread starts run on ``count`` threads (0: one per core).

    numba's thread count is a setting of the thread that starts a parallel
    kernel, so a solve thread can take fewer cores than the machine has and
    leave one to the image callback, which starts serial kernels only (the
    ``solve_threads`` parameter; docs/node.md has the measurements). A
    kernel's result does not depend on it: its blocks of pixels are fixed.
    Returns the count now in effect.
    """
    most = numba.config.NUMBA_NUM_THREADS
    numba.set_num_threads(min(int(count), most) if count else most)
    return numba.get_num_threads()


def typed_frames(frames):
    """
    Return a sequence of frames (each (C, n)) as a numba typed list of C-ordered float32 arrays.

    A kernel that reads the frames where they are takes one compiled type
    whatever their count (a window's buffered columns, without a stack);
    each frame is copied only where it is not C-ordered float32 already.
    """
    return List([np.ascontiguousarray(frame, dtype=np.float32) for frame in frames])


def reference_unless(compiled, reference, *args):
    """
    Return ``compiled(*args)``, or ``reference(*args)`` where the pass returned None.

    A pass returns None for the inputs whose answers it does not promise to
    reproduce (another dtype, a value its arithmetic cannot follow); its
    numpy reference then answers.
    """
    result = compiled(*args)
    return reference(*args) if result is None else result


@dataclass(frozen=True)
class CompiledPass:
    """
    A compiled pass, its numpy reference and the examples that warm it up and check it.

    Attributes
    ----------
    name : str
        ``module.function`` of the pass.
    compiled, reference : callable
        The pass and its numpy reference: the same arguments, the same
        results (a pass may return None where the reference answers).
    examples : callable
        Returns fresh argument tuples (each called afresh: a pass may write
        into its arguments), every specialisation the package's callers
        compile among them.
    atol, rtol : float
        Largest absolute and relative differences allowed to the reference
        (``numpy.testing.assert_allclose``'s); both 0.0: bit for bit. A pass
        compiled with ``fastmath`` reassociates its sums, so it agrees with
        its reference to rounding only.

    """

    name: str
    compiled: Callable
    reference: Callable
    examples: Callable
    atol: float = 0.0
    rtol: float = 0.0

    def warm_up(self):
        """Compile (or load from the cache) the pass on each of its examples."""
        for args in self.examples():
            self.compiled(*args)


#: Every registered pass, in registration order (:func:`register_pass`).
PASSES = []


def register_pass(compiled, examples, reference=None, atol=0.0, rtol=0.0):
    """Register a pass, its examples and its reference; return its :class:`CompiledPass`."""
    name = f'{compiled.__module__.removeprefix("dgmod_ros.")}.{compiled.__name__}'
    PASSES.append(CompiledPass(name, compiled, reference, examples, atol, rtol))
    return PASSES[-1]
