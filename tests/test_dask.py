"""The Dask executor against a real scheduler and two workers, each its own process on 127.0.0.1.

``distributed`` is imported, not ``importorskip``-ed: the dev install (``.[dev,cluster]``) has it, and these
tests must fail rather than silently skip when it is missing.
"""

import json
import os
import signal
import subprocess
import sys
import time

import distributed  # noqa: F401 - the cluster extra is part of the dev install: fail, never skip, without it
import pytest

from amronet.cli import main
from amronet.experiments.runner import run_jobs
from amronet.sweeps import DaskExecutor, LocalExecutor, run_sweep, sweep_from_spec
from sweep_helpers import runs_in, same_store_content, tiny_sweep, write_sweep


def start_cluster(tmp, workers=2):
    """A scheduler and ``workers`` one-thread workers, each its own process; returns ``(address, procs)``."""
    info = tmp / "scheduler.json"
    common = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "cwd": tmp}
    procs = [subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                               "--port", "0", "--no-dashboard", "--scheduler-file", str(info),
                               "--idle-timeout", "300s"], **common)]
    try:
        deadline = time.monotonic() + 60
        while not info.exists() and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2)
        address = json.loads(info.read_text())["address"]
        for k in range(workers):
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1", "--nworkers", "1",
                 "--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--name", f"w{k}", "--death-timeout", "60",
                 "--local-directory", str(tmp / f"w{k}")], **common))
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(workers, timeout=60)
    except BaseException:
        stop_cluster(procs)
        raise
    return address, procs


def stop_cluster(procs):
    for proc in reversed(procs):
        if proc.poll() is None:
            proc.terminate()
    for proc in reversed(procs):
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    address, procs = start_cluster(tmp_path_factory.mktemp("dask"))
    try:
        yield address
    finally:
        stop_cluster(procs)


def test_sweep_on_dask_equals_the_local_pool(scheduler, tmp_path):
    sweep = sweep_from_spec(tiny_sweep(radii=(0.8, 1.0, 1.2), seeds=3))
    with DaskExecutor(scheduler=scheduler) as dask:
        assert dask.slots == 2 and "127.0.0.1" in dask.describe()
        report = run_sweep(sweep, tmp_path / "dask.sqlite", dask, show_progress=False)
    assert (report.total, report.done, report.failed) == (9, 9, 0)
    run_sweep(sweep, tmp_path / "local.sqlite", LocalExecutor(2), show_progress=False)
    assert same_store_content(tmp_path / "dask.sqlite", tmp_path / "local.sqlite")


def test_cli_scheduler_and_run_jobs_on_dask(scheduler, tmp_path, capsys):
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep(seeds=2))
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--scheduler", scheduler]) == 0
    assert "4 runs: 0 already in the store, 4 done" in capsys.readouterr().out
    sc = {"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"count": 10},
          "sim": {"time_limit": 3.0}}
    jobs = [{"scenario": sc, "seed": s, "labels": {"k": s}} for s in (3, 1, 2)]
    with DaskExecutor(scheduler=scheduler) as dask:
        on_dask = run_jobs(jobs, show_progress=False, executor=dask)
    local = run_jobs(jobs, workers=1, show_progress=False)
    assert [r["labels"] for r in on_dask] == [{"k": 3}, {"k": 1}, {"k": 2}]
    assert [r["summary"]["coverage"] for r in on_dask] == [r["summary"]["coverage"] for r in local]


def test_without_dask_the_scheduler_option_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--scheduler", "tcp://127.0.0.1:1"]) == 2
    err = capsys.readouterr().err
    assert "pip install 'amronet[cluster]'" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "r.sqlite").exists()


def test_losing_the_scheduler_mid_sweep_is_one_line_and_keeps_the_finished_runs(tmp_path):
    address, procs = start_cluster(tmp_path, workers=2)
    spec = {"name": "lost", "base": "self-spreading-6x6", "overrides": {"sim.time_limit": 150.0},
            "grid": {"radio.r_c": [0.8, 1.0, 1.2]}, "seeds": 10}
    path = write_sweep(tmp_path / "sweep.yaml", spec)
    store = tmp_path / "lost.sqlite"
    cmd = [sys.executable, "-m", "amronet.cli", "sweep", str(path), "--store", str(store), "--scheduler", address,
           "-q"]
    sweep = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while runs_in(store) < 2 and sweep.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert sweep.poll() is None, "the sweep should still be running when the scheduler goes"
        os.kill(procs[0].pid, signal.SIGKILL)  # the scheduler, like a lost node
        _, err = sweep.communicate(timeout=120)
    finally:
        if sweep.poll() is None:
            sweep.kill()
            sweep.wait()
        stop_cluster(procs)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("amronet: error: lost the Dask cluster (") and "Traceback" not in err
    assert f"the finished runs are in {str(store)!r}: run the same command again to resume" in lines[0]
    assert sweep.returncode == 2
    kept = runs_in(store)
    assert 2 <= kept < 30
    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "--json", "-q"]) == 0


@pytest.mark.parametrize("address", ["nonsense", "tcp://127.0.0.1:notaport", "nosuchproto://127.0.0.1:8786"])
def test_a_malformed_scheduler_address_is_one_line(tmp_path, capsys, address):
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--scheduler", address]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"amronet: error: --scheduler: {address!r} is not a scheduler address ("), err
    assert "\n" not in err and not (tmp_path / "r.sqlite").exists()
