# Copyright 2026 dgmod_ros authors
# Licensed under the Apache License, Version 2.0
"""The solver thread reports every exception and never dies; ``busy`` never sticks."""

import threading

from dgmod_ros.solve_worker import SolveWorker
import pytest


class Recorder:
    """Callbacks that record what the worker reports, optionally raising themselves."""

    def __init__(self, done_raises=False, error_raises=False):
        self.done, self.errors = [], []
        self.done_raises, self.error_raises = done_raises, error_raises

    def on_done(self, job, result):
        self.done.append((job, result))
        if self.done_raises:
            raise AttributeError('on_done broke')

    def on_error(self, job, error):
        self.errors.append((job, error))
        if self.error_raises:
            raise AttributeError('on_error broke too')


def _solve(job):
    if job == 'bad':
        raise KeyError('solve broke')
    return job * 2


@pytest.fixture
def make_worker():
    workers = []

    def make(recorder, solve=_solve):
        worker = SolveWorker(solve, recorder.on_done, recorder.on_error)
        workers.append(worker)
        return worker
    yield make
    for worker in workers:
        assert worker.stop(timeout=5.0)


def _run(worker, job):
    assert worker.submit(job)
    assert worker.wait_idle(timeout=10.0)
    assert not worker.busy


def test_results_and_solve_errors_are_reported(make_worker):
    recorder = Recorder()
    worker = make_worker(recorder)
    _run(worker, 3)
    _run(worker, 'bad')
    _run(worker, 4)
    assert recorder.done == [(3, 6), (4, 8)]
    assert [(job, type(error)) for job, error in recorder.errors] == [('bad', KeyError)]


def test_an_exception_in_on_done_goes_to_on_error(make_worker):
    recorder = Recorder(done_raises=True)
    worker = make_worker(recorder)
    _run(worker, 1)
    _run(worker, 2)
    assert [job for job, _ in recorder.done] == [1, 2]
    assert [type(error) for _, error in recorder.errors] == [AttributeError, AttributeError]
    assert worker.callback_errors == 0


@pytest.mark.parametrize('job', ['bad', 5])
def test_an_exception_in_on_error_is_counted_and_the_thread_goes_on(make_worker, job):
    # The failure of issue 11: install raised, then drop_warm_start raised in
    # the error handler, the thread died and busy stuck for ever.
    recorder = Recorder(done_raises=True, error_raises=True)
    worker = make_worker(recorder)
    _run(worker, job)
    assert worker.callback_errors == 1
    assert 'on_error broke too' in worker.last_callback_error
    recorder.done_raises = recorder.error_raises = False
    _run(worker, 7)
    assert recorder.done[-1] == (7, 14)


def test_one_job_at_a_time_without_a_queue(make_worker):
    started, release = threading.Event(), threading.Event()

    def blocking(job):
        started.set()
        assert release.wait(10.0)
        return job

    recorder = Recorder()
    worker = make_worker(recorder, blocking)
    assert worker.submit('first')
    assert started.wait(10.0)
    assert worker.busy and not worker.submit('second')      # refused, not queued
    release.set()
    assert worker.wait_idle(10.0)
    assert recorder.done == [('first', 'first')]


@pytest.mark.filterwarnings('ignore::pytest.PytestUnhandledThreadExceptionWarning')
def test_a_thread_killed_by_a_base_exception_is_replaced(make_worker):
    def fatal(job):
        if job == 'exit':
            raise SystemExit('solver thread killed')
        return job

    recorder = Recorder()
    worker = make_worker(recorder, fatal)
    _run(worker, 'exit')                      # busy is cleared even so
    worker._thread.join(10.0)
    assert not worker._thread.is_alive()
    _run(worker, 'next')                      # submit starts a new thread
    assert recorder.done == [('next', 'next')]


def test_the_initializer_runs_in_the_worker_thread_and_may_fail(caplog):
    recorder, names = Recorder(), []
    worker = SolveWorker(_solve, recorder.on_done, recorder.on_error, name='dgmod-test',
                         initializer=lambda: names.append(threading.current_thread().name))
    try:
        _run(worker, 3)
    finally:
        assert worker.stop(timeout=5.0)
    assert names == ['dgmod-test'] and recorder.done == [(3, 6)]

    def broken():
        raise RuntimeError('no threads today')

    recorder = Recorder()
    worker = SolveWorker(_solve, recorder.on_done, recorder.on_error, initializer=broken)
    try:
        _run(worker, 4)                       # logged; the thread solves without it
    finally:
        assert worker.stop(timeout=5.0)
    assert recorder.done == [(4, 8)] and recorder.errors == []
    assert 'no threads today' in caplog.text
