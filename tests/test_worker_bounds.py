"""``--workers`` is bounded (issue #45): never more processes than runs, more than the cores only with ``--force``,
never more than the memory holds (:mod:`amronet.sweeps.worker_bounds`, through every pool amronet starts)."""

from __future__ import annotations

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from unittest import mock

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet import limits
from amronet.cli import main
from amronet.errors import AmronetError
from amronet.sweeps import local_pool, worker_bounds
from amronet.sweeps.engine import run_sweep
from amronet.sweeps.executors import LocalExecutor, make_executor
from amronet.sweeps.spec import sweep_from_spec
from amronet.sweeps.worker_bounds import check_workers, default_workers, pool_size
from sweep_helpers import tiny_sweep, write_sweep

GiB = 1024**3
LINUX = sys.platform.startswith("linux")


@pytest.fixture
def machine(monkeypatch):
    """A machine of 2 cores and 64 GiB available unless a test says otherwise: ``machine(cores, memory)``."""

    def set_machine(cores: int = 2, memory: int | None = 64 * GiB) -> None:
        monkeypatch.setattr(worker_bounds, "available_cores", lambda: cores)
        monkeypatch.setattr(limits, "available_memory", lambda: memory)

    set_machine()
    return set_machine


def pool_workers() -> list[int]:
    """Pids of this process's children but multiprocessing's resource tracker (from /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and int((entry / "stat").read_bytes().rsplit(b")", 1)[1].split()[1]) == \
                    os.getpid() and b"resource_tracker" not in (entry / "cmdline").read_bytes():
                out.append(int(entry.name))
        except (OSError, IndexError):
            continue
    return out


# -- the bound ---------------------------------------------------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(workers=st.one_of(st.none(), st.integers(-3, 10**7)), cores=st.integers(1, 256), force=st.booleans(),
       memory=st.one_of(st.none(), st.integers(0, 2**44)))
def test_workers_are_bounded_by_cores_unless_forced_and_by_memory_always(workers, cores, force, memory):
    with mock.patch.object(worker_bounds, "available_cores", lambda: cores), \
            mock.patch.object(limits, "available_memory", lambda: memory):
        fits = memory is None or (workers or 0) * limits.BYTES_PER_WORKER <= memory
        try:
            got = check_workers(workers, force)
        except AmronetError as exc:
            line = str(exc)
            assert "\n" not in line and line.startswith("--workers: ")
            assert workers is not None and workers != 1
            if workers < 1:
                assert "must be >= 1" in line
            elif workers > cores and not force:
                assert f"more than the {cores} cores" in line and f"give --workers {cores} or fewer, or --force" in line
            else:
                assert not fits and "of memory, but" in line and "--force does not change this" in line
                fit = max(memory // limits.BYTES_PER_WORKER, 1)
                assert f"give --workers {fit} or fewer" in line
            return
        if workers is None:
            assert got == default_workers() and 1 <= got <= cores
            assert memory is None or got == 1 or got * limits.BYTES_PER_WORKER <= memory
        else:
            assert got == workers and (workers == 1 or ((workers <= cores or force) and fits))


@given(workers=st.integers(1, 10**6), jobs=st.integers(0, 10**6))
def test_a_pool_never_starts_more_processes_than_jobs(workers, jobs):
    assert pool_size(workers, jobs) == max(1, min(workers, jobs))


def test_every_pool_asks_the_bound_first(machine):
    with pytest.raises(AmronetError, match=r"^--workers: 100,000 worker processes are more than the 2 cores"):
        LocalExecutor(100_000)
    with pytest.raises(AmronetError, match=r"^--workers: 3 worker processes are more than the 2 cores"):
        make_executor(workers=3)
    machine(memory=GiB)
    with pytest.raises(AmronetError, match=r"would need about 12.2 TiB of memory, but 1 GiB are available; give "
                                           r"--workers 8 or fewer \(--force does not change this\)"):
        make_executor(workers=100_000, force=True)
    assert LocalExecutor(8, force=True).workers == 8 and LocalExecutor().workers == 2
    pytest.importorskip("distributed")
    with mock.patch("distributed.LocalCluster") as cluster:  # refused before a LocalCluster starts
        with pytest.raises(AmronetError, match=r"^--workers: 100,000 worker processes \(128 MiB each\) would need"):
            make_executor(workers=100_000, cluster="local", force=True)
        cluster.assert_not_called()


@pytest.mark.skipif(not LINUX, reason="counts the workers through /proc")
def test_a_pool_starts_no_more_processes_than_jobs_and_grows_up_to_its_workers(machine):
    before = set(pool_workers())
    with LocalExecutor(3, force=True) as ex:
        assert sorted(ex.imap_unordered(abs, [-1, -2])) == [(0, 1), (1, 2)]
        assert ex.started == 2 and len(set(pool_workers()) - before) == 2
        assert sorted(r for _, r in ex.imap_unordered(abs, [-1, -2, -3, -4, -5])) == [1, 2, 3, 4, 5]
        assert ex.started == 3 and len(set(pool_workers()) - before) == 3
        assert sorted(ex.imap_unordered(abs, [-7, -8])) == [(0, 7), (1, 8)]
        assert ex.started == 3  # a larger pool serves fewer jobs as it is
    assert ex.started == 0


@pytest.mark.skipif(not LINUX, reason="counts the workers through /proc")
def test_a_two_run_sweep_on_three_workers_starts_two(tmp_path, machine):
    sweep = sweep_from_spec(tiny_sweep(radii=(0.8, 1.0), seeds=1))
    before = set(pool_workers())
    with LocalExecutor(3, force=True) as ex:
        report = run_sweep(sweep, tmp_path / "r.sqlite", ex, show_progress=False)
        assert report.done == 2 and ex.started == 2 and len(set(pool_workers()) - before) == 2


# -- the command line --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["sweep", "reproduce", "plan"])
def test_a_hundred_thousand_workers_are_one_line_and_start_nothing(tmp_path, capsys, machine, command):
    cores = worker_bounds.available_cores()
    args = {"sweep": ["sweep", str(write_sweep(tmp_path / "tiny.yaml", tiny_sweep())), "--store",
                      str(tmp_path / "r.sqlite")],
            "reproduce": ["reproduce", "fig10", "--quick", "--out", str(tmp_path / "out")],
            "plan": ["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "8", "--out", str(tmp_path / "out")]}
    before, t0 = set(pool_workers()) if LINUX else set(), time.perf_counter()
    assert main([*args[command], "--workers", "100000", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"amronet: error: --workers: 100,000 worker processes are more than the {cores} cores this "
                   f"process may use; give --workers {cores} or fewer, or --force to start them anyway "
                   "(force=True in Python)")
    machine(memory=4 * GiB)
    assert main([*args[command], "--workers", "100000", "--force", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("amronet: error: --workers: 100,000 worker processes")
    assert "but 4 GiB are available; give --workers 32 or fewer (--force does not change this)" in err
    assert time.perf_counter() - t0 < 20
    assert not (tmp_path / "r.sqlite").exists() and not (tmp_path / "out").exists()
    assert not LINUX or set(pool_workers()) <= before


@pytest.mark.skipif(not LINUX, reason="counts the workers through /proc")
def test_sweep_of_two_runs_with_three_workers_starts_at_most_two(tmp_path, capsys, monkeypatch, machine):
    counts: list[int] = []

    class Counted(ProcessPoolExecutor):
        def shutdown(self, *args, **kwargs) -> None:
            counts.append(len(pool_workers()))  # the pool's processes, all forked at its first job
            super().shutdown(*args, **kwargs)

    monkeypatch.setattr(local_pool, "ProcessPoolExecutor", Counted)
    path = write_sweep(tmp_path / "tiny.yaml", tiny_sweep(radii=(0.8, 1.0), seeds=1))
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--workers", "3", "--force", "-q"]) == 0
    assert counts and max(counts) <= 2, counts
