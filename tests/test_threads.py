"""amronet.threads: which kernels run on several threads, and a thread pool that survives fork."""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor

import numba
import numpy as np
import pytest

from amronet import threads
from amronet.engine import neighbours
from amronet.sweeps.worker import on_one_thread, start_worker


def test_only_large_calls_use_threads(monkeypatch):
    monkeypatch.setattr(threads, "_serial", False)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 2)
    assert not threads.use_threads(threads.MIN_ITEMS - 1)
    assert threads.use_threads(threads.MIN_ITEMS)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 1)  # one core: no threads
    assert not threads.use_threads(10 * threads.MIN_ITEMS)


def test_a_serial_process_never_uses_threads(monkeypatch):
    monkeypatch.setattr(threads, "_serial", False)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 2)
    threads.serial_only()
    assert not threads.use_threads(10 * threads.MIN_ITEMS)


def test_numba_gets_a_fork_safe_pool_unless_the_user_chose_one(monkeypatch):
    monkeypatch.delenv("NUMBA_THREADING_LAYER", raising=False)
    monkeypatch.setattr(numba.config, "THREADING_LAYER", "default")
    threads.configure()
    assert numba.config.THREADING_LAYER == "forksafe"
    monkeypatch.setenv("NUMBA_THREADING_LAYER", "omp")
    monkeypatch.setattr(numba.config, "THREADING_LAYER", "omp")
    threads.configure()
    assert numba.config.THREADING_LAYER == "omp"


def _worker_may_use_threads(_: int) -> bool:
    return threads.use_threads(10 * threads.MIN_ITEMS)


def test_a_sweeps_workers_run_their_kernels_on_one_thread():
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"), initializer=start_worker,
                             initargs=(os.getpid(), False)) as pool:
        assert pool.submit(_worker_may_use_threads, 0).result(timeout=60) is False


def _threaded_search(n: int) -> int:
    neighbours.use_threads = lambda n: True  # this process only (a forked child)
    xy = np.random.default_rng(n).uniform(0.0, 20.0, (n, 2))
    return int(neighbours.neighbour_csr(xy, 1.0)[0][-1])


def test_a_child_forked_after_a_threaded_kernel_can_run_one(monkeypatch):
    """GNU OpenMP's pool hangs a forked child; the pool amronet picks does not (sweeps fork their workers)."""
    monkeypatch.setattr(neighbours, "use_threads", lambda n: True)
    expected = _threaded_search(2000)  # the pool is started in this process
    if numba.threading_layer() not in ("workqueue", "tbb"):
        pytest.skip(f"the user chose the {numba.threading_layer()!r} layer")
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork")) as pool:
        assert pool.submit(_threaded_search, 2000).result(timeout=120) == expected


def test_a_clusters_jobs_run_their_kernels_on_one_thread(monkeypatch):
    """Dask runs one job per core: every job goes through ``on_one_thread`` (the executor maps it)."""
    monkeypatch.setattr(threads, "_serial", False)
    monkeypatch.setattr(numba.config, "NUMBA_NUM_THREADS", 2)
    assert on_one_thread(_worker_may_use_threads, 0) is False
    assert on_one_thread(lambda job: job + 1, 41) == 42
