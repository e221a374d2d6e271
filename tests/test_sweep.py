import csv
import json
import re

import pytest
from PIL import Image

from amronet.cli import main
from amronet.errors import AmronetError
from amronet.experiments.runner import run_jobs
from amronet.sweeps import ResultStore
from sweep_helpers import tiny_sweep, write_sweep


@pytest.fixture
def swept(tmp_path, capsys):
    spec = tiny_sweep(grid={"radio.r_c": [0.8, 1.0], "algorithm.params.triangular": ["local", "none"]})
    path = write_sweep(tmp_path / "sweep.yaml", spec)
    store = tmp_path / "results.sqlite"
    assert main(["sweep", str(path), "--store", str(store), "--workers", "2"]) == 0
    return path, store, capsys.readouterr().out


def test_sweep_prints_a_table_and_resumes_nothing_twice(swept, capsys):
    path, store, out = swept
    assert "nodes_total" in out and "8 runs: 0 already in the store, 8 done" in out
    header = next(line for line in out.splitlines() if "nodes_total" in line)
    assert "radio.r_c" not in header and re.search(r"\br_c\b.*\btriangular\b", header)  # short names
    assert re.search(r"\b0\.8 +. local +. +2/2", out)  # the point's values, not its index
    assert main(["sweep", str(path), "--store", str(store), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["runs"], doc["already_in_store"], doc["done_now"]) == (8, 8, 0)
    assert [p["runs"] for p in doc["points"]] == [2, 2, 2, 2]
    assert all(len(p["scenario_hash"]) == 64 for p in doc["points"])
    assert main(["sweep", str(path), "--store", str(store), "--hash"]) == 0
    assert doc["points"][0]["scenario_hash"][:12] in capsys.readouterr().out


def test_sweep_table_gives_mean_and_ci_to_the_same_decimal_place(swept):
    _, _, out = swept
    cells = re.findall(r"(-?\d+(?:\.(\d+))?) ± (\d+(?:\.(\d+))?)", out)
    assert len(cells) == 4
    for _, mean_decimals, half, half_decimals in cells:
        assert mean_decimals == "" or len(mean_decimals) == len(half_decimals)
        if float(half) > 0:  # the half-width to two significant digits
            assert len(half.replace(".", "").lstrip("0")) == 2


def test_results_name_runs_by_their_point_and_keep_the_hash_for_scripts(swept, capsys):
    _, store, _ = swept
    with ResultStore(store) as st:
        hashes = {r["scenario_hash"][:12] for r in st.runs()}
    assert main(["results", str(store), "--limit", "0"]) == 0
    out = capsys.readouterr().out
    assert "r_c=0.8, triangular=local" in out and "r_c=1.0, triangular=none" in out
    assert not any(h in out for h in hashes)
    rows = [line for line in out.splitlines() if "r_c=" in line]
    assert len(rows) == 8 and "r_c=0.8, triangular=local" in rows[0]  # in point order
    assert main(["results", str(store), "--hash"]) == 0
    out = capsys.readouterr().out
    assert all(h in out for h in hashes)
    assert main(["results", str(store), "--json"]) == 0
    runs = json.loads(capsys.readouterr().out)["runs"]
    assert {r["scenario_hash"][:12] for r in runs} == hashes
    assert {(r["point"]["radio.r_c"], r["point"]["algorithm.params.triangular"]) for r in runs} == {
        (0.8, "local"), (0.8, "none"), (1.0, "local"), (1.0, "none")}


def test_results_lists_and_exports_tidy_tables(swept, tmp_path, capsys):
    _, store, _ = swept
    assert main(["results", str(store)]) == 0
    out = capsys.readouterr().out
    assert "tiny" in out and "done" in out
    assert main(["results", str(store), "--export", "csv", "--out", str(tmp_path / "csv")]) == 0
    runs = list(csv.DictReader((tmp_path / "csv" / "runs.csv").open()))
    assert len(runs) == 8 and {r["radio.r_c"] for r in runs} == {"0.8", "1.0"}
    assert {"nodes_total", "coverage", "algorithm.params.triangular", "states.explore"} <= set(runs[0])
    links = list(csv.DictReader((tmp_path / "csv" / "sweep_runs.csv").open()))
    assert len(links) == 8 and links[0]["sweep"] == "tiny"
    ts = list(csv.DictReader((tmp_path / "csv" / "timeseries.csv").open()))
    assert len(ts) > 8 and "agents_connected" not in ts[0]
    pq = pytest.importorskip("pyarrow.parquet")
    assert main(["results", str(store), "--export", "parquet", "--out", str(tmp_path / "pq"), "--sweep",
                 "tiny"]) == 0
    table = pq.read_table(tmp_path / "pq" / "runs.parquet")
    assert table.num_rows == 8 and str(table.schema.field("radio.r_c").type) == "double"
    assert str(table.schema.field("nodes_total").type) == "int64"


def test_results_limit(swept, capsys):
    _, store, _ = swept
    assert main(["results", str(store), "--limit", "3"]) == 0
    assert "... and 5 more runs (--limit 0 shows all)" in capsys.readouterr().out
    assert main(["results", str(store), "--limit", "0"]) == 0
    assert "more runs" not in capsys.readouterr().out
    assert main(["results", str(store), "--limit", "-1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("amronet: error: --limit: -1 must be >= 0 (the number of runs to list; 0 lists them all)")


def test_plot_draws_mean_and_ci(swept, tmp_path, capsys):
    _, store, _ = swept
    out = tmp_path / "plot.png"
    assert main(["plot", str(store), "--x", "radio.r_c", "--y", "nodes_total", "--hue",
                 "algorithm.params.triangular", "--out", str(out)]) == 0
    assert Image.open(out).size[0] > 400 and "4 points from 8 runs" in capsys.readouterr().out
    for name in ("cat.svg", "cat2.svg"):
        assert main(["plot", str(store), "--x", "algorithm.params.triangular", "--y", "coverage", "--out",
                     str(tmp_path / name)]) == 0
    assert (tmp_path / "cat.svg").read_bytes() == (tmp_path / "cat2.svg").read_bytes()
    assert main(["plot", str(store), "--x", "radio.rc", "--y", "nodes_total", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--x: no column 'radio.rc'" in err and "radio.r_c" in err and len(err.strip().splitlines()) == 1


def test_results_and_plot_of_a_missing_store_are_one_line(tmp_path, capsys):
    assert main(["results", str(tmp_path / "none.sqlite")]) == 2
    assert main(["plot", str(tmp_path / "none.sqlite"), "--x", "a", "--y", "b", "--out", "p.png"]) == 2
    assert capsys.readouterr().err.count("no result store") == 2
    assert not (tmp_path / "none.sqlite").exists()


def _jobs(timeseries=False):
    sc = {"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"count": 10},
          "sim": {"time_limit": 3.0}}
    return [{"scenario": sc, "seed": s, "labels": {"k": s}, "timeseries": timeseries} for s in (3, 1, 2, 3)]


def test_run_jobs_with_a_store_gives_the_same_results_and_resumes(tmp_path):
    plain = run_jobs(_jobs(True), workers=1, show_progress=False)
    store = tmp_path / "r.sqlite"
    first = run_jobs(_jobs(True), workers=2, show_progress=False, store=store)
    seen = []
    again = run_jobs(_jobs(True), workers=2, show_progress=False, store=store, on_result=lambda k, r: seen.append(k))
    assert sorted(seen) == [0, 1, 2, 3]
    for a, b, c in zip(plain, first, again, strict=True):
        assert a["labels"] == b["labels"] == c["labels"] and a["seed"] == b["seed"]
        assert a["timeseries"] == b["timeseries"] == c["timeseries"]
        drop = ("wall_time_s", "scenario")
        assert {k: v for k, v in a["summary"].items() if k not in drop} == \
            {k: v for k, v in b["summary"].items() if k not in drop}
        assert b["summary"] == c["summary"]
    with ResultStore(store) as st:
        assert len(st.runs()) == 3 and st.sweeps()[0]["name"] == "runs"
    no_ts = run_jobs(_jobs(False), workers=1, show_progress=False, store=store)
    assert "timeseries" not in no_ts[0]


def test_run_jobs_with_a_store_raises_after_recording_failures(tmp_path):
    jobs = _jobs()
    jobs[1] = {**jobs[1], "scenario": {**jobs[1]["scenario"], "base_stations": [{"x": 2.999, "y": 0}]}}
    with pytest.raises(AmronetError, match="1 of 3 runs failed"):
        run_jobs(jobs, workers=1, show_progress=False, store=tmp_path / "r.sqlite")
    with ResultStore(tmp_path / "r.sqlite") as st:
        assert sorted(r["status"] for r in st.runs()) == ["done", "done", "failed"]


def test_reproduce_keeps_its_store_in_the_output_folder(tmp_path, capsys):
    out = tmp_path / "f7"
    args = ["reproduce", "fig7", "--quick", "--explorer", "random", "--time-limit", "200", "--workers", "2",
            "--out", str(out), "-q"]
    assert main(args) == 0
    first = (out / "fig7_runs.csv").read_text()
    with ResultStore(out / "results.sqlite") as st:
        stamps = {(r["scenario_hash"], r["seed"]): r["wall_time_s"] for r in st.runs()}
    assert len(stamps) == 8
    assert main(args) == 0  # every run comes from the store: same table, no run repeated
    assert (out / "fig7_runs.csv").read_text() == first
    with ResultStore(out / "results.sqlite") as st:
        assert {(r["scenario_hash"], r["seed"]): r["wall_time_s"] for r in st.runs()} == stamps


def test_parquet_without_pyarrow_is_one_line(swept, tmp_path, capsys, monkeypatch):
    import sys

    _, store, _ = swept
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    assert main(["results", str(store), "--export", "parquet", "--out", str(tmp_path / "pq")]) == 2
    err = capsys.readouterr().err
    assert "pip install 'amronet[cluster]'" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "pq").exists()


def _die_on_seed_1(job):
    """A sweep job that kills its worker process (like the out-of-memory killer) when it holds seed 1."""
    import os
    import signal

    from amronet.sweeps.worker import execute_batch

    if 1 in job["seeds"]:
        os.kill(os.getpid(), signal.SIGKILL)
    return execute_batch(job)


def test_a_dead_worker_is_one_line_and_the_pool_can_run_again():
    import os

    from amronet.sweeps.executors import LocalExecutor, WorkerDiedError

    with LocalExecutor(2) as ex:
        with pytest.raises(WorkerDiedError, match=r"a worker process died \(killed, or out of memory\?\)"):
            list(ex.imap_unordered(os._exit, [3, 3, 3]))
        assert sorted(ex.imap_unordered(abs, [-1, -2])) == [(0, 1), (1, 2)]


def test_a_sweep_whose_worker_dies_keeps_its_runs_and_resumes(tmp_path, capsys, monkeypatch):
    import amronet.sweeps.engine as engine

    path = write_sweep(tmp_path / "sweep.yaml", tiny_sweep(seeds=[0, 1, 2]))
    store = tmp_path / "results.sqlite"
    monkeypatch.setattr(engine, "execute_batch", _die_on_seed_1)
    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: a worker process died") and len(err.splitlines()) == 1
    assert f"the finished runs are kept in {str(store)!r}: run the same command again to resume" in err
    with ResultStore(store) as st:
        assert all(r["status"] == "done" and r["seed"] != 1 for r in st.runs())
    monkeypatch.undo()
    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["runs"] == 6 and doc["failed"] == 0 and doc["already_in_store"] + doc["done_now"] == 6


def test_plot_without_out_writes_a_default_file_in_the_current_folder(swept, tmp_path, capsys, monkeypatch):
    _, store, _ = swept
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    assert main(["plot", str(store), "--x", "radio.r_c", "--y", "nodes_total", "--hue", "algorithm"]) == 0
    name = "plot-nodes_total-vs-radio.r_c-by-algorithm.png"
    assert capsys.readouterr().out.startswith(f"wrote {name}: nodes_total vs radio.r_c by algorithm")
    assert Image.open(tmp_path / name).size[0] > 400
    assert main(["plot", str(store), "--x", "radio.r_c", "--y", "coverage"]) == 0
    assert (tmp_path / "plot-coverage-vs-radio.r_c.png").is_file()


def test_results_and_plot_name_the_positional_store(tmp_path, capsys):
    notes = tmp_path / "notes.txt"
    notes.write_text("not a store\n")
    assert main(["results", str(tmp_path / "none.sqlite")]) == 2
    assert main(["plot", str(notes), "--x", "a", "--y", "b"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("amronet: error: STORE: no result store at")
    assert err[1].startswith("amronet: error: STORE: ") and "not a SQLite database" in err[1]
    assert "--store" not in err[1]


@pytest.mark.parametrize("extra", [[], ["--json"]])
def test_results_into_a_closed_pipe_stops_quietly(swept, extra):
    import subprocess
    import sys

    _, store, _ = swept
    proc = subprocess.Popen([sys.executable, "-m", "amronet.cli", "results", str(store), "--limit", "0", *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # like `| head -1` once it has its line
    err = proc.stderr.read().decode()
    assert proc.wait() == 1 and err == ""


def test_workers_with_a_scheduler_is_one_line(tmp_path, capsys):
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--workers", "2", "--scheduler",
                 "tcp://127.0.0.1:1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("amronet: error: --workers: ") and "--scheduler" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "r.sqlite").exists()


def test_run_jobs_retries_failed_runs_only_when_told_to(tmp_path):
    jobs = _jobs()
    bad = {**jobs[1], "scenario": {**jobs[1]["scenario"], "base_stations": [{"x": 2.999, "y": 0}]}}
    store = tmp_path / "r.sqlite"
    with pytest.raises(AmronetError, match="1 of 3 runs failed"):
        run_jobs([jobs[0], bad, jobs[2]], workers=1, show_progress=False, store=store)
    with ResultStore(store) as st:
        stamps = {(r["scenario_hash"], r["seed"]): r["finished_at"] for r in st.runs()}
    with pytest.raises(AmronetError, match=r"1 of 3 runs failed .*retry them with retry_failed"):
        run_jobs([jobs[0], bad, jobs[2]], workers=1, show_progress=False, store=store, retry_failed=False)
    with ResultStore(store) as st:
        assert {(r["scenario_hash"], r["seed"]): r["finished_at"] for r in st.runs()} == stamps  # not run again
    with pytest.raises(AmronetError, match="1 of 3 runs failed"):
        run_jobs([jobs[0], bad, jobs[2]], workers=1, show_progress=False, store=store, retry_failed=True)


class _LosesTheCluster:
    """An executor whose cluster goes away after the first job (a batch of runs of one scenario)."""

    slots = 1
    first_job_runs = 0

    def imap_unordered(self, fn, jobs):
        from amronet.sweeps.executors import ClusterLostError

        self.first_job_runs = len(jobs[0]["seeds"])
        yield 0, fn(jobs[0])
        raise ClusterLostError("scheduler-connection-lost")

    def describe(self):
        return "a vanishing cluster"

    def close(self):
        pass


def test_a_lost_cluster_is_one_error_that_keeps_the_finished_runs(tmp_path):
    from amronet.sweeps import run_sweep, sweep_from_spec
    from amronet.sweeps.executors import ClusterLostError

    store = tmp_path / "r.sqlite"
    executor = _LosesTheCluster()
    with pytest.raises(ClusterLostError) as info:
        run_sweep(sweep_from_spec(tiny_sweep()), store, executor, show_progress=False)
    assert str(info.value) == (f"lost the Dask cluster (scheduler-connection-lost); the finished runs are in "
                               f"{str(store)!r}: run the same command again to resume")
    with ResultStore(store) as st:
        assert len(st.runs()) == executor.first_job_runs == 2  # the two seeds of the first point, one batch
