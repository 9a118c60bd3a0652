# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The fused numba sweep against the literal numpy sweep, and kernels from two threads."""

import ctypes
from dataclasses import replace
import os
from pathlib import Path
import subprocess
import sys
import threading
import types

from dgmod_ros.core import kernel_cache
from dgmod_ros.core.dgmod import DualGraphMOD
from dgmod_ros.core.kernels import dgmod as kernels
from dgmod_ros.core.linalg import c_order, frames_major, gram_matrix
from dgmod_ros.core.runtime import limit_blas_threads
from dgmod_ros.core.synthetic import synthetic_scene
from fresh_process import fresh_python
import numba
import numpy as np
import pytest

SHAPE = (36, 48)
FRAMES = 24
STATE = ('background', 'foreground', 'low_rank', 'noise', 'dual_low_rank', 'dual_noise')


def scene_window(frames=FRAMES, seed=0):
    scene = synthetic_scene(n_frames=frames, shape=SHAPE, seed=seed)
    grey = scene.frames.mean(axis=3) / 255.0
    return np.ascontiguousarray(grey.reshape(frames, -1).T, dtype=np.float32)


def assert_same_iterates(a, b, atol):
    for name in STATE:
        x, y = getattr(a.state_, name), getattr(b.state_, name)
        assert x.dtype == y.dtype == np.float32
        assert np.abs(x - y).max() <= atol, name
    assert np.allclose(a.state_.weights, b.state_.weights, atol=1e-4)
    assert a.history_['rank'] == b.history_['rank']
    for key in ('change_L', 'change_S', 'residual_U', 'residual_V'):
        assert np.allclose(a.history_[key], b.history_[key], rtol=1e-3, atol=1e-7), key


@pytest.mark.parametrize('options', [
    {},                                        # the default: one gradient step, fused L-step
    {'l_step': 'exact', 'inner_iter': 2},      # L-step in numpy, the rest fused
    {'inner_iter': 2},
    {'lambda1': 0.0},                          # no nuclear norm: identity prox
    {'lambda2': 1.5, 'gamma1': 0.0},           # residual goes to V: the V-shrinkage matters
])
def test_fused_sweep_gives_the_numpy_iterates(options):
    data = scene_window()
    sweeps = 12
    numpy_model = DualGraphMOD(engine='numpy', tol=1e-12, max_iter=sweeps, **options)
    fused_model = DualGraphMOD(engine='fused', tol=1e-12, max_iter=sweeps, **options)
    numpy_model.fit(data, SHAPE)
    fused_model.fit(data, SHAPE)
    assert numpy_model.n_iter_ == fused_model.n_iter_ == sweeps
    # float32 rounding differs (fused sums, band order); 12 sweeps stay within 1e-4.
    assert_same_iterates(numpy_model, fused_model, atol=1e-4)


@pytest.mark.parametrize('frames', [1, 2, 5, 7, 12])
def test_block_gram_and_u_are_the_products_for_any_window_length(frames):
    # The Gram matrix goes by 3 x 4 tiles, which the window length need not fill.
    rows = np.random.default_rng(frames).random((frames, 70)).astype(np.float32)
    gram = np.zeros((frames, frames))
    kernels._add_block_gram(rows, 5, 66, gram)
    block = rows[:, 5:66].astype(np.float64)
    upper = np.triu_indices(frames)
    assert np.allclose(gram[upper], (block @ block.T)[upper], rtol=1e-5)
    # The whole window's, symmetric, as linalg.gram_matrix takes it from a
    # frames-major window (and from BLAS for any other).
    whole = kernels.frames_gram_reference(rows)
    for window in (rows.T, np.ascontiguousarray(rows.T)):
        assert np.allclose(gram_matrix(window), whole, rtol=1e-5)
    assert np.array_equal(gram_matrix(rows.T), gram_matrix(rows.T).T)
    left = np.random.default_rng(1).random((3, frames)).astype(np.float32)
    right = np.random.default_rng(2).random((frames, 3)).astype(np.float32)
    out = kernels._block_u(rows, 5, 66, left, right)
    assert out.shape == (frames, 61) and out.dtype == np.float32
    assert np.allclose(out, right @ (left @ block), rtol=1e-5)


def test_fused_solve_stops_where_numpy_stops_and_warm_starts_alike():
    data = scene_window()
    first = [DualGraphMOD(engine=e, tol=1e-3).fit(data[:, :-4], SHAPE) for e in ('numpy', 'fused')]
    assert first[0].info_ == first[1].info_ == 0
    assert abs(first[0].n_iter_ - first[1].n_iter_) <= 1
    init = first[0].state_.shifted(4)
    second = [DualGraphMOD(engine=e, tol=1e-12, max_iter=5).fit(data[:, 4:], SHAPE, init=init)
              for e in ('numpy', 'fused')]
    assert_same_iterates(second[0], second[1], atol=1e-4)


@pytest.mark.parametrize('shift', [0, 4])
def test_fused_solve_reads_its_warm_start_without_writing_it(shift):
    # The fused pass updates V, Y2 and Lh in place and swaps L and S with
    # its own buffers: a warm start, which with a shift of 0 is the previous
    # model's own state, must come out as it went in.
    data = scene_window()
    previous = DualGraphMOD(tol=1e-3).fit(data[:, :-4], SHAPE)
    init = previous.state_.shifted(shift)
    before = {name: getattr(init, name).copy() for name in STATE}
    window = data[:, shift:data.shape[1] - 4 + shift]
    for max_iter in (1, 2, 5):
        model = DualGraphMOD(tol=1e-12, max_iter=max_iter).fit(window, SHAPE, init=init)
        assert model.n_iter_ == max_iter
        for name in STATE:
            assert np.array_equal(getattr(init, name), before[name]), name
            assert not np.shares_memory(getattr(model.state_, name), getattr(init, name)), name


@pytest.mark.filterwarnings('ignore:overflow encountered', 'ignore:invalid value encountered')
def test_non_finite_iterate_stops_both_engines_alike():
    # A gradient step far beyond 1 / Lipschitz diverges to inf within a few sweeps.
    data = scene_window()
    models = [DualGraphMOD(engine=e, step_size=1e6, max_iter=50).fit(data, SHAPE)
              for e in ('numpy', 'fused')]
    for model in models:
        assert model.info_ == -1
        assert np.isfinite(model.background_).all() and np.isfinite(model.foreground_).all()
    assert models[0].n_iter_ == models[1].n_iter_
    # The fused pass updates V, Y2 and Lh in place: its state restarts them
    # from the last finite L and S rather than handing non-finite duals on.
    fused = models[1].state_
    for name in STATE:
        assert np.isfinite(getattr(fused, name)).all(), name
    assert np.array_equal(fused.low_rank, fused.background)
    assert not fused.dual_low_rank.any() and not fused.dual_noise.any()


def test_converged_engines_reach_the_same_objective():
    # The engines stop a sweep apart; at tol 1e-4 their objectives (the
    # literal reference's full SVD included) agree to 5e-6 relative here,
    # while 60 more sweeps (tol 3e-5) still lower it by 1.7e-4.
    data = scene_window()
    models = [DualGraphMOD(**options).fit(data, SHAPE)
              for options in ({}, {'engine': 'numpy'}, {'engine': 'numpy', 'svd': 'full'})]
    values = [model.objective(data, SHAPE) for model in models]
    for model in models:
        assert model.info_ == 0
    assert max(values) - min(values) <= 5e-5 * min(values), values
    # Not a vacuous bound: the objective at the median start is 44% higher.
    start = DualGraphMOD(max_iter=1).fit(data, SHAPE)
    assert start.objective(data, SHAPE) > 1.3 * min(values)


def test_kernels_run_from_two_threads_at_once():
    # The node calls kernels from its image callback and its solve thread;
    # numba's workqueue layer would stop the process here.
    data = [scene_window(seed=seed) for seed in (1, 2)]
    alone = [DualGraphMOD(tol=1e-12, max_iter=8).fit(d, SHAPE) for d in data]
    barrier = threading.Barrier(2)
    together = [None, None]
    errors = []

    def solve(index):
        try:
            barrier.wait(timeout=30)
            for _ in range(5):
                together[index] = DualGraphMOD(tol=1e-12, max_iter=8).fit(data[index], SHAPE)
        except Exception as error:      # reported below, in the main thread
            errors.append(error)

    threads = [threading.Thread(target=solve, args=(i,)) for i in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=300)
    assert not errors
    assert numba.threading_layer() in ('tbb', 'omp')
    for a, b in zip(alone, together):
        assert_same_iterates(a, b, atol=1e-6)


def test_cache_folder_defaults_to_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    assert kernel_cache.default_cache_dir() == str(tmp_path / 'dgmod_ros' / 'numba')
    assert numba.config.CACHE_DIR       # set before the first compiled call
    assert numba.config.THREADING_LAYER == 'threadsafe'


def test_openblas_runs_on_one_thread_after_a_fused_solve():
    import scipy.linalg  # noqa: F401 (scipy's own OpenBLAS, loaded after the kernels)
    DualGraphMOD(max_iter=1).fit(scene_window(), SHAPE)
    getters = ('openblas_get_num_threads', 'openblas_get_num_threads64_',
               'scipy_openblas_get_num_threads', 'scipy_openblas_get_num_threads64_')
    with open('/proc/self/maps') as maps:
        paths = {line.split()[-1] for line in maps
                 if 'openblas' in line.lower() and '.so' in line}
    counts = []
    for path in paths:
        library = ctypes.CDLL(path)
        counts += [getattr(library, name)() for name in getters if hasattr(library, name)][:1]
    if not counts:
        pytest.skip('no OpenBLAS loaded (another BLAS: nothing to limit)')
    assert set(counts) == {1}
    assert limit_blas_threads(1) == len(counts)


def test_blas_libraries_are_read_again_only_after_an_import(monkeypatch):
    from dgmod_ros.core import runtime
    limited = limit_blas_threads(1)
    reads = []
    real_open = open

    def counting_open(path, *args, **kwargs):
        reads.append(path)
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(runtime, 'open', counting_open, raising=False)
    assert limit_blas_threads(1) == limited and reads == []
    monkeypatch.setitem(sys.modules, 'dgmod_test_extension', types.ModuleType('extension'))
    assert limit_blas_threads(1) == limited and reads == ['/proc/self/maps']


def test_threading_layer_survives_numba_imported_first(tmp_path):
    # A module that imports numba before dgmod_ros.core.numba_setup, then a
    # compile: numba re-reads its configuration from the environment, which
    # must keep the threadsafe layer (the node calls kernels from two threads).
    script = (
        'import os\n'
        'os.environ.pop("NUMBA_THREADING_LAYER", None)\n'
        'os.environ.pop("NUMBA_CACHE_DIR", None)\n'
        'import numba\n'
        'from dgmod_ros.core import numba_setup\n'
        '@numba.njit\n'
        'def one_more(x):\n'
        '    return x + 1\n'
        'one_more(1)\n'
        'print(numba.config.THREADING_LAYER)\n')
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path))
    assert fresh_python(script, env).strip() == 'threadsafe'


# Run in a fresh interpreter: compile_all, then the detector on read-only
# frames (a frame viewing a message's bytes is read-only) in several
# configurations; print every kernel specialisation compiled after compile_all.
_LATE_COMPILES = """
import sys
from numba.core.registry import CPUDispatcher
from dgmod_ros import config
from dgmod_ros.core.warmup import compile_all
from dgmod_ros.core.synthetic import synthetic_scene
import numpy as np

def specialisations():
    return {(name, attr): set(map(str, obj.signatures))
            for name, module in list(sys.modules.items()) if name.startswith('dgmod_ros')
            for attr, obj in vars(module).items() if isinstance(obj, CPUDispatcher)}

compile_all()
warm = specialisations()
scene = synthetic_scene(n_frames=40, shape=(120, 160), seed=1)
depth = (scene.frames.mean(axis=3) * 20).astype(np.uint16)       # a 16-bit one-channel camera
cases = [({}, scene.frames, 'rgb', None), ({}, scene.frames[..., ::-1], 'bgr', None),
         ({'scale': 1.0}, scene.frames, 'rgb', None),
         ({'color': 'gray'}, depth, 'rgb', 5100.0)]
for overrides, frames, order, value_range in cases:
    detector = config.build_detector(dict(config.DEFAULTS, **overrides))
    for frame in list(frames) * 2:
        frame = np.array(frame)
        frame.setflags(write=False)
        detector.process(frame, order, value_range)
for key, signatures in specialisations().items():
    for signature in sorted(signatures - warm.get(key, set())):
        print(*key, signature)
"""


def test_compile_all_covers_every_kernel_the_detector_calls():
    # A kernel compiled (or loaded from the cache) on its first call holds the
    # GIL for 50-250 ms: in the node that stalls the image callback and loses
    # frames. compile_all, called at configure, must leave none to the first frames.
    done = subprocess.run([sys.executable, '-c', _LATE_COMPILES], capture_output=True,
                          text=True, cwd=str(Path(__file__).resolve().parents[1]),
                          timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout == '', f'compiled after compile_all:\n{done.stdout}'


def test_frames_major_and_c_order_are_transposes_without_needless_copies():
    matrix = scene_window()
    frames = frames_major(matrix)
    assert frames.flags.c_contiguous and np.array_equal(frames, matrix.T)
    # The solver's F-ordered state: its transpose is the frames-major array itself.
    assert np.shares_memory(frames_major(frames.T), frames)
    for source in (matrix, frames.T, matrix[::2]):      # C, F, strided
        ordered = c_order(source)
        assert ordered.flags.c_contiguous and np.array_equal(ordered, source)
    assert c_order(matrix) is matrix


def test_fused_state_is_frames_major_and_warm_starts_as_a_c_ordered_copy():
    data = scene_window()
    first = DualGraphMOD(tol=1e-3).fit(data[:, :-4], SHAPE)
    for name in STATE:
        assert getattr(first.state_, name).flags.f_contiguous, name
    init = first.state_.shifted(4)
    copied = replace(init, **{name: np.ascontiguousarray(getattr(init, name)) for name in STATE})
    again = [DualGraphMOD(tol=1e-12, max_iter=5).fit(data[:, 4:], SHAPE, init=start)
             for start in (init, copied)]
    # The memory order is no input of the solver: the same iterates bit for bit.
    assert_same_iterates(again[0], again[1], atol=0.0)
