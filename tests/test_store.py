import sqlite3

import pytest

from amronet.errors import ScenarioError
from amronet.sweeps import LocalExecutor, ResultStore, StoreError, run_sweep, sweep_from_spec
from amronet.sweeps.worker import execute_job
from sweep_helpers import same_store_content, tiny_sweep


def _outcome(sweep, k=0):
    p, seed = sweep.runs()[k]
    return p, seed, execute_job({"scenario": p.scenario, "seed": seed})


def test_record_and_load_round_trip_bit_for_bit(tmp_path):
    sweep = sweep_from_spec(tiny_sweep())
    p, seed, out = _outcome(sweep)
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.record(p.hash, seed, p.scenario, out)
        loaded = store.load(p.hash, seed)
        assert store.load(p.hash, seed + 100) is None
    assert loaded["status"] == "done"
    assert {k: v for k, v in loaded["summary"].items() if k not in ("wall_time_s", "amronet_version", "scenario")} \
        == out["summary"]
    assert loaded["summary"]["scenario"] == p.scenario
    assert loaded["timeseries"] == out["timeseries"]


def test_store_is_wal_and_ours(tmp_path):
    path = tmp_path / "r.sqlite"
    ResultStore(path).close()
    con = sqlite3.connect(path)
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert con.execute("PRAGMA application_id").fetchone()[0] == 0x414D524E
    tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    assert {"runs", "timeseries", "sweeps", "sweep_runs"} <= tables


@pytest.mark.parametrize("content", [b"hello, not a database\n", b"SQLite format 3\x00" + b"\x00" * 10])
def test_a_file_that_is_not_a_store_is_refused_untouched(tmp_path, content):
    path = tmp_path / "r.sqlite"
    path.write_bytes(content)
    with pytest.raises(StoreError, match="not a SQLite database") as info:
        ResultStore(path)
    assert "\n" not in str(info.value)
    assert path.read_bytes() == content and sorted(p.name for p in tmp_path.iterdir()) == ["r.sqlite"]


def test_another_sqlite_database_is_refused_untouched(tmp_path):
    path = tmp_path / "other.db"
    con = sqlite3.connect(path)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    before = path.read_bytes()
    with pytest.raises(StoreError, match="not an amronet result store"):
        ResultStore(path)
    assert path.read_bytes() == before


def test_folder_and_missing_store(tmp_path):
    with pytest.raises(StoreError, match="is a folder"):
        ResultStore(tmp_path)
    with pytest.raises(StoreError, match="no result store"):
        ResultStore(tmp_path / "missing.sqlite", must_exist=True)
    assert not (tmp_path / "missing.sqlite").exists()


def test_failed_runs_are_recorded_and_retried_only_when_asked(tmp_path):
    # x = 2.999 puts the base station inside the field's wall: the fields validate, the run raises (a sweep
    # refuses such a point up front; check_start=False lets it through to exercise failed runs)
    spec = tiny_sweep(radii=(1.0,), points=[{"base_stations.0.x": 2.999}], seeds=2)
    with pytest.raises(ScenarioError, match=r"^points\[0\]\.base_stations\[0\]: \(2.999, 0\) is inside"):
        sweep_from_spec(spec)
    sweep = sweep_from_spec(spec, check_start=False)
    store = tmp_path / "r.sqlite"
    first = run_sweep(sweep, store, LocalExecutor(1), show_progress=False)
    assert (first.total, first.done, first.failed) == (4, 2, 2)
    with ResultStore(store) as st:
        failed = [r for r in st.runs() if r["status"] == "failed"]
    assert len(failed) == 2 and all("base_stations[0]" in r["error"] and "\n" not in r["error"] for r in failed)
    assert failed[0]["summary"] is None and failed[0]["nodes_total"] is None
    again = run_sweep(sweep, store, LocalExecutor(1), show_progress=False)
    assert (again.already, again.done, again.failed) == (4, 0, 0)
    retried = run_sweep(sweep, store, LocalExecutor(1), show_progress=False, retry_failed=True)
    assert (retried.already, retried.done, retried.failed) == (2, 0, 2)
    with ResultStore(store) as st:
        assert len(st.runs()) == 4 and st.sweeps()[0]["failed"] == 2


def test_a_run_shared_by_two_sweeps_runs_once(tmp_path):
    store = tmp_path / "r.sqlite"
    a = run_sweep(sweep_from_spec(tiny_sweep(name="a", radii=(0.8, 1.0))), store, LocalExecutor(1),
                  show_progress=False)
    b = run_sweep(sweep_from_spec(tiny_sweep(name="b", radii=(1.0, 1.2))), store, LocalExecutor(1),
                  show_progress=False)
    assert (a.done, b.already, b.done) == (4, 2, 2)
    with ResultStore(store) as st:
        assert len(st.runs()) == 6
        assert [(s["name"], s["runs"], s["done"]) for s in st.sweeps()] == [("a", 4, 4), ("b", 4, 4)]
        assert len(st.runs(st.find_sweep("b"))) == 4
        with pytest.raises(StoreError, match="no sweep 'c'"):
            st.find_sweep("c")


def test_same_sweep_same_rows_whatever_the_workers(tmp_path):
    sweep = sweep_from_spec(tiny_sweep(seeds=3))
    run_sweep(sweep, tmp_path / "one.sqlite", LocalExecutor(1), show_progress=False)
    with LocalExecutor(2) as pool:
        run_sweep(sweep, tmp_path / "two.sqlite", pool, show_progress=False)
    assert same_store_content(tmp_path / "one.sqlite", tmp_path / "two.sqlite")
