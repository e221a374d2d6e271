"""The Dask executor against a real scheduler and two workers, each its own process on 127.0.0.1."""

import json
import subprocess
import sys
import time

import pytest

from amronet.cli import main
from amronet.experiments.runner import run_jobs
from amronet.sweeps import DaskExecutor, LocalExecutor, run_sweep, sweep_from_spec
from sweep_helpers import same_store_content, tiny_sweep, write_sweep

pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dask")
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
        for k in range(2):
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1", "--nworkers", "1",
                 "--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--name", f"w{k}", "--death-timeout", "60",
                 "--local-directory", str(tmp / f"w{k}")], **common))
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in reversed(procs):
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


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
