# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""
Where the compiled kernels live, whether they are there, and how they get there without a stall.

numba compiles the package's compiled passes (``dgmod_ros/core/kernels/``,
``dgmod_ros/core/streaming/kernels/``) once and keeps them in a disk cache; a cold compile takes
30-60 s on two cores and holds the GIL, so it must not happen in a process
that is meant to answer a user or a camera (docs/node.md, "First start").

- **The cache folder** is ``$NUMBA_CACHE_DIR``, else
  ``$XDG_CACHE_HOME/dgmod_ros/numba``, else ``~/.cache/dgmod_ros/numba``
  (:func:`cache_dir`; :mod:`~dgmod_ros.core.numba_setup` sets
  ``NUMBA_CACHE_DIR`` to it before numba reads its configuration). numba
  keys an entry by the source file's absolute path, its mtime and size, the
  numba version and the CPU: an entry is valid only for the installed files
  it was compiled from.
- **The install's seed.** ``colcon build`` (``setup.py install``) compiles
  every kernel against the files it has just installed, into
  ``dgmod_ros/kernel_seed/`` beside them (``setup.py``'s ``install_kernels``).
  :func:`seed_cache` copies the seed's files into the cache folder where they
  are missing or older, so a fresh home folder, or a read-only install
  prefix, loads them instead of compiling.
- **The ready mark.** :func:`mark_ready` (the end of
  :func:`~dgmod_ros.core.warmup.compile_all`) writes one small file per
  installed package into the cache folder holding :func:`cache_key`: the
  sources' paths, mtimes and sizes, the numba and Python versions and the
  CPU. :func:`is_ready` compares it with the running install's key, so a
  process knows before it loads anything whether a load will be a compile.
- **A compile in a child process** (:class:`ChildCompile`): when the
  cache is not ready, a child fills it while the caller waits in short
  sleeps, so Ctrl-C and SIGTERM stop the caller at once (the child is
  ended with it); the caller then loads the cache in about 2 s.

No numba import here: the checks run before numba is loaded.
"""

import hashlib
import json
import os
from pathlib import Path
import platform
import shutil
import subprocess
import sys
import tempfile
import time

# Seconds a cold compile took on the project's 2-core VM (docs/node.md,
# "First start": 35-55 s at load 2-10); what the first log line says
# until this machine has measured one itself (:func:`expected_compile_seconds`).
TYPICAL_COMPILE_SECONDS = 40
# The package folder (dgmod_ros/), as numba sees the sources: an absolute
# path, symlinks not resolved (numba's cache uses os.path.abspath).
PACKAGE_DIR = Path(os.path.abspath(__file__)).parents[1]
SEED_NAME = 'kernel_seed'
_READY_PREFIX = 'dgmod_ros-ready-'


def default_cache_dir():
    """Return the user's folder for the compiled-kernel cache (module docstring)."""
    base = os.environ.get('XDG_CACHE_HOME') or str(Path.home() / '.cache')
    return str(Path(base) / 'dgmod_ros' / 'numba')


def cache_dir():
    """Return the folder numba caches the kernels in: ``$NUMBA_CACHE_DIR``, else the default."""
    return os.environ.get('NUMBA_CACHE_DIR') or default_cache_dir()


def seed_dir(package_dir=PACKAGE_DIR):
    """Return the folder the install compiled the kernels into (it may not exist)."""
    return Path(package_dir) / SEED_NAME


def seed_cache(target=None, seed=None):
    """
    Copy the install's compiled kernels into the cache folder where they are missing or older.

    An entry the cache already holds at least as new as the seed's is kept
    (the user's process may have added specialisations to an index since).
    Returns the number of files copied; 0 where there is no seed.
    """
    seed = Path(seed) if seed is not None else seed_dir()
    target = Path(target or cache_dir())
    if not seed.is_dir():
        return 0
    copied = 0
    try:
        for source in seed.rglob('*'):
            copied += _copy_if_newer(source, target / source.relative_to(seed))
    except OSError:
        pass        # a cache folder that takes no files: numba says so when it compiles
    return copied


def _copy_if_newer(source, destination):
    if not source.is_file():
        return 0
    try:
        if destination.stat().st_mtime >= source.stat().st_mtime:
            return 0
    except FileNotFoundError:
        pass
    destination.parent.mkdir(parents=True, exist_ok=True)
    # Into a temporary name, then renamed: a process that loads the cache
    # meanwhile sees the old file or the new one, never half of one.
    handle, temporary = tempfile.mkstemp(dir=destination.parent, prefix='.seed-')
    os.close(handle)
    shutil.copy2(source, temporary)
    os.replace(temporary, destination)
    return 1


def _host_cpu():
    # numba's cache keys an entry by the CPU too (its codegen's name and
    # features): the processor's model and flags change with them, read
    # without loading LLVM.
    try:
        with open('/proc/cpuinfo') as info:
            fields = dict(map(str.strip, line.split(':', 1)) for line in info if ':' in line)
        return [fields.get('model name', ''), fields.get('flags', '')]
    except OSError:
        return [platform.machine(), platform.processor()]


def _numba_version():
    try:
        from importlib.metadata import version
        return version('numba')
    except Exception:  # noqa: B902 - not installed: nothing can compile anyway
        return None


def cache_key(package_dir=PACKAGE_DIR):
    """
    Return what the cache's entries depend on, for this install (a JSON-able dict).

    Every source of ``dgmod_ros/core`` counts (any of them may hold a
    kernel): its path, mtime and size, as numba stamps an entry; then the
    numba and Python versions and the CPU.
    """
    core = Path(package_dir) / 'core'
    sources = []
    for path in sorted(core.rglob('*.py')):
        status = path.stat()
        sources.append([str(path), status.st_mtime_ns, status.st_size])
    return {'sources': sources, 'numba': _numba_version(),
            'python': platform.python_version(), 'cpu': _host_cpu()}


def ready_path(folder=None, package_dir=PACKAGE_DIR):
    """Return the ready mark's path for the install at ``package_dir`` (one per install)."""
    tag = hashlib.sha1(str(package_dir).encode()).hexdigest()[:16]
    return Path(folder or cache_dir()) / f'{_READY_PREFIX}{tag}.json'


def is_ready(folder=None, package_dir=PACKAGE_DIR):
    """Return whether the cache holds every kernel compiled for this install (its ready mark)."""
    try:
        mark = json.loads(ready_path(folder, package_dir).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(mark, dict) and mark.get('key') == cache_key(package_dir)


def mark_ready(seconds=None, folder=None, package_dir=PACKAGE_DIR):
    """Write the ready mark (after every kernel was compiled or loaded); keeps a compile's time."""
    path = ready_path(folder, package_dir)
    previous = {}
    try:
        previous = json.loads(path.read_text())
    except (OSError, ValueError):
        pass
    mark = {'key': cache_key(package_dir),
            'compile_seconds': seconds if seconds is not None
            else previous.get('compile_seconds')}
    if mark == previous:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix='.ready-')
    with os.fdopen(handle, 'w') as stream:
        json.dump(mark, stream)
    os.replace(temporary, path)
    return path


def expected_compile_seconds(folder=None):
    """Return how long a cold compile should take here: the last one measured, else typical."""
    measured = []
    for path in Path(folder or cache_dir()).glob(_READY_PREFIX + '*.json'):
        try:
            seconds = json.loads(path.read_text()).get('compile_seconds')
        except (OSError, ValueError, AttributeError):
            continue
        if isinstance(seconds, (int, float)) and seconds > 0:
            measured.append((path.stat().st_mtime, seconds))
    return max(measured)[1] if measured else TYPICAL_COMPILE_SECONDS


class CompileFailed(RuntimeError):
    """The child process that compiles the kernels failed (its output is in the message)."""


class CompileInterrupted(RuntimeError):
    """The caller asked to stop while the child compiled (the child was ended)."""


class ChildCompile:
    """
    A compile of every kernel into the cache, in a child process started at once.

    The caller goes on (the node imports its modules meanwhile) and
    :meth:`wait` s when it needs the kernels, in short sleeps, so a signal
    (Ctrl-C's KeyboardInterrupt) or ``should_stop`` (an rclpy shutdown)
    interrupts it at once; the child is then ended (SIGTERM, then SIGKILL)
    before the exception goes on. numba writes each cache file under a
    temporary name and renames it, so an ended child leaves a cache without
    torn files (and no ready mark). The child ignores SIGINT: Ctrl-C at a
    terminal reaches the whole process group, and the caller, not the child,
    decides what it means.
    """

    def __init__(self):
        # The child imports the very files the caller runs (numba keys the
        # cache by their paths): the package's parent folder first, and no
        # current folder (-P).
        code = ('import sys; sys.path.insert(0, {!r}); '
                'from dgmod_ros.core.warmup import child_main; child_main()').format(
                    str(PACKAGE_DIR.parent))
        env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir())
        self.started = time.monotonic()
        self._output = tempfile.TemporaryFile(mode='w+')
        self._child = subprocess.Popen([sys.executable, '-P', '-c', code], env=env,
                                       stdin=subprocess.DEVNULL, stdout=self._output,
                                       stderr=subprocess.STDOUT)

    @property
    def pid(self):
        """Return the child's process id."""
        return self._child.pid

    def wait(self, progress=None, should_stop=None, poll=0.1, report_every=10.0):
        """
        Wait for the child; return the seconds since it started.

        ``progress(elapsed)`` is called every ``report_every`` s. Raises
        :class:`CompileInterrupted` when ``should_stop()`` turns true,
        :class:`CompileFailed` when the child fails; any exception (a
        KeyboardInterrupt) ends the child first.
        """
        next_report = self.started + report_every
        try:
            while self._child.poll() is None:
                if should_stop is not None and should_stop():
                    raise CompileInterrupted('stopped while compiling the kernels')
                time.sleep(poll)
                if progress is not None and time.monotonic() >= next_report:
                    next_report += report_every
                    progress(time.monotonic() - self.started)
        finally:
            self.stop()
        with self._output:
            self._output.seek(0)
            if self._child.returncode != 0:
                raise CompileFailed(f'the kernel compile exited with {self._child.returncode}: '
                                    f'{self._output.read()[-2000:].strip()}')
        return time.monotonic() - self.started

    def stop(self, grace=1.0):
        """End the child if it still runs (SIGTERM, SIGKILL after ``grace`` s)."""
        if self._child.poll() is None:
            self._child.terminate()
            try:
                self._child.wait(grace)
            except subprocess.TimeoutExpired:
                self._child.kill()
                self._child.wait()


def start_compile(log=None, say_ready=False):
    """
    Start a :class:`ChildCompile` unless the cache is ready for this install; say so.

    Copies the install's seed first (:func:`seed_cache`). Returns the
    compile, or None when there is nothing to compile (``log``ged too with
    ``say_ready``).
    """
    seed_cache()
    if is_ready():
        if log is not None and say_ready:
            log(f'starting: kernels compiled for this install, loading them from {cache_dir()}')
        return None
    compile_ = ChildCompile()
    try:
        if log is not None:
            log(f'compiling kernels, once per install, about {expected_compile_seconds():.0f} s '
                f'(numba cache {cache_dir()}); Ctrl-C stops it')
    except BaseException:
        compile_.stop()         # a signal before the caller holds the child
        raise
    return compile_


def ensure_ready(log=None, pending=None, should_stop=None):
    """
    Make the cache ready for this install, compiling in a child where it is not.

    ``pending`` is a compile already started (:func:`start_compile`), else
    one is started here if needed. Returns the compile's seconds, 0.0 where
    the cache was ready. A failed child is logged and left to the caller's
    own load (which then compiles in process, as without this module).
    """
    if pending is None:
        pending = start_compile(log)
        if pending is None:
            return 0.0
    say = log or (lambda message: None)
    try:
        seconds = pending.wait(
            progress=lambda elapsed: say(f'still compiling kernels: {elapsed:.0f} s'),
            should_stop=should_stop)
    except CompileFailed as error:
        say(f'{error}; compiling in this process instead')
        return 0.0
    say(f'kernels compiled in {seconds:.0f} s (cached in {cache_dir()})')
    return seconds
