"""Faults around a sweep (issue #18): a killed parent, lost Dask workers, two sweeps on one store, racing creators.

* Killing only the parent of a local pool (``kill -9``) leaves no worker behind: the kernel's parent-death signal
  on Linux and a watchdog thread in every worker; the interrupted sweep then resumes without losing or repeating
  a finished run.
* With every Dask worker gone the sweep stops after ``--worker-timeout`` seconds with one line (it used to wait
  forever), keeping the finished runs.
* Two sweeps on one store at the same time compute every run once (a claim per run in the store); a claim whose
  owner died is taken over.
* Twenty processes creating one new store at the same instant all succeed, and the store is healthy.
"""

import json
import multiprocessing
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from amronet.cli import main
from amronet.sweeps import ResultStore, sweep_from_spec
from amronet.sweeps.worker import execute_job
from sweep_helpers import children, runs_in, tiny_sweep, write_sweep
from test_dask import start_cluster, stop_cluster

LINUX = sys.platform.startswith("linux")
AMRONET = [sys.executable, "-m", "amronet.cli"]


def slow_sweep(name, points=(0.8, 1.0, 1.2), seeds=3, time_limit=100.0):
    """Runs of a few tenths of a second each (self-spreading on the 6 m field)."""
    return {"name": name, "base": "self-spreading-6x6", "overrides": {"sim.time_limit": time_limit},
            "grid": {"radio.r_c": list(points)}, "seeds": seeds}



def pool_workers(pid):
    """Pids of ``pid``'s children but multiprocessing's resource tracker (a helper a process pool may start)."""
    out = []
    for child in children(pid):
        try:
            if b"resource_tracker" not in Path(f"/proc/{child}/cmdline").read_bytes():
                out.append(child)
        except OSError:
            continue
    return out


def alive(pid):
    """Whether process ``pid`` runs: it exists and (where /proc tells) is not a zombie."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        state = Path(f"/proc/{pid}/stat").read_bytes().rsplit(b")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in (b"Z", b"X")


def wait_until(condition, timeout, step=0.02):
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(step)
    return True


def kill_group(proc):
    """SIGKILL what is left of a process started with ``start_new_session`` (its group), and reap it."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


# -- orphaned workers -----------------------------------------------------------------------------------------------
@pytest.mark.skipif(not LINUX, reason="finds the workers through /proc")
def test_kill_9_of_the_parent_leaves_no_worker_and_the_sweep_resumes(tmp_path):
    path = write_sweep(tmp_path / "sweep.yaml", slow_sweep("orphans"))
    store = tmp_path / "o.sqlite"
    cmd = [*AMRONET, "sweep", str(path), "--store", str(store), "--workers", "2", "-q"]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        # up to a minute more where the kernels' cache has no note of a warm-up for this version of them (a source
        # change since `make` ran `amronet compile`): the sweep then compiles the common kernels first, on a pool
        # of its own (amronet.sim.warmup.warm_up_if_cold), whose resource tracker stays; with the note, its first
        # run is in within a few seconds
        assert wait_until(lambda: len(pool_workers(proc.pid)) == 2 and runs_in(store) >= 1, 180), \
            "no workers, no runs"
        helpers = children(proc.pid)  # the workers and the resource tracker if any
        os.kill(proc.pid, signal.SIGKILL)  # only the parent: its workers are not signalled
        proc.wait()
        assert wait_until(lambda: not any(alive(w) for w in helpers), 10), "workers outlived their parent"
    finally:
        kill_group(proc)
    survived = dict(sqlite3.connect(store).execute("SELECT scenario_hash || ':' || seed, wall_time_s FROM runs"))
    assert 1 <= len(survived) < 9, "the kill should land part-way"

    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "-q"]) == 0
    con = sqlite3.connect(store)
    after = dict(con.execute("SELECT scenario_hash || ':' || seed, wall_time_s FROM runs"))
    assert len(after) == 9
    assert all(after[k] == wall for k, wall in survived.items()), "a finished run was run again"
    assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


WATCHDOG_PARENT = textwrap.dedent("""
    import ctypes, os, sys, threading, time
    from concurrent.futures import ProcessPoolExecutor
    from amronet.sweeps.worker import guard_worker

    def probe(_):
        value = ctypes.c_int(-1)
        if sys.platform.startswith("linux"):
            ctypes.CDLL(None).prctl(2, ctypes.byref(value), 0, 0, 0)  # PR_GET_PDEATHSIG
        return os.getpid(), value.value, sorted(t.name for t in threading.enumerate())

    if __name__ == "__main__":
        death_signal = sys.argv[1] == "signal"
        pool = ProcessPoolExecutor(1, initializer=guard_worker, initargs=(os.getpid(), death_signal))
        print(*pool.submit(probe, 0).result(), sep=";", flush=True)
        time.sleep(120)
""")


@pytest.mark.parametrize("guard", ["watchdog", "signal"])
def test_each_guard_alone_ends_a_worker_whose_parent_was_killed(tmp_path, guard):
    """The watchdog on its own (as on systems without a parent-death signal); and the signal (Linux)."""
    if guard == "signal" and not LINUX:
        pytest.skip("PR_SET_PDEATHSIG is Linux only")
    script = tmp_path / "parent.py"
    script.write_text(WATCHDOG_PARENT)
    proc = subprocess.Popen([sys.executable, str(script), guard], start_new_session=True, stdout=subprocess.PIPE,
                            text=True)
    try:
        pid, deathsig, threads = proc.stdout.readline().strip().split(";")
        worker = int(pid)
        assert "amronet-parent-watchdog" in threads
        if LINUX:
            assert int(deathsig) == (signal.SIGKILL if guard == "signal" else 0)
        if guard == "signal":  # stop the watchdog, so that only the kernel's signal is left to end the worker
            os.kill(worker, signal.SIGSTOP)
        assert alive(worker)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        assert wait_until(lambda: not alive(worker), 10), f"the {guard} did not end the worker"
    finally:
        kill_group(proc)


# -- all Dask workers lost ------------------------------------------------------------------------------------------
def test_all_dask_workers_lost_stops_after_the_worker_timeout_with_one_line(tmp_path):
    address, procs = start_cluster(tmp_path, workers=2)
    path = write_sweep(tmp_path / "sweep.yaml", slow_sweep("workerless", seeds=4))
    store = tmp_path / "w.sqlite"
    cmd = [*AMRONET, "sweep", str(path), "--store", str(store), "--scheduler", address, "--worker-timeout", "3", "-q"]
    sweep = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert wait_until(lambda: runs_in(store) >= 1 or sweep.poll() is not None, 90)
        assert sweep.poll() is None, "the sweep should still be running when its workers go"
        for worker in procs[1:]:
            worker.kill()  # every worker is lost; the scheduler stays up and would wait for new ones forever
        for worker in procs[1:]:
            worker.wait(timeout=30)
        start = time.monotonic()
        _, err = sweep.communicate(timeout=60)
        waited = time.monotonic() - start
    finally:
        if sweep.poll() is None:
            sweep.kill()
            sweep.wait()
        stop_cluster(procs)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("amronet: error: lost the Dask cluster (no worker for 3 s;")
    assert f"the finished runs are in {str(store)!r}: run the same command again to resume" in lines[0]
    assert sweep.returncode == 2 and waited < 30
    assert 1 <= runs_in(store) < 12


def test_worker_timeout_goes_with_dask_only(tmp_path, capsys):
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--worker-timeout", "5"]) == 2
    err = capsys.readouterr().err
    assert "--worker-timeout: only with --scheduler ADDRESS or --cluster local" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "r.sqlite").exists()
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--cluster", "local",
                 "--worker-timeout", "-1"]) == 2
    assert "--worker-timeout: must be a number of seconds >= 0" in capsys.readouterr().err


# -- two sweeps on one store ----------------------------------------------------------------------------------------
def counting_store(path):
    """A new store whose ``recorded`` table counts every run written to it (a trigger), so a run computed twice
    shows even though its row is replaced."""
    ResultStore(path).close()
    con = sqlite3.connect(path)
    con.executescript("CREATE TABLE recorded (scenario_hash TEXT, seed INTEGER);"
                      "CREATE TRIGGER count_runs AFTER INSERT ON runs BEGIN "
                      "INSERT INTO recorded VALUES (NEW.scenario_hash, NEW.seed); END;")
    con.close()


def recorded(path):
    con = sqlite3.connect(path)
    try:
        return con.execute("SELECT scenario_hash, seed, COUNT(*) FROM recorded GROUP BY scenario_hash, seed").fetchall()
    finally:
        con.close()


def test_two_sweeps_at_once_on_one_store_compute_every_run_once(tmp_path):
    path = write_sweep(tmp_path / "sweep.yaml", slow_sweep("twice"))
    store = tmp_path / "t.sqlite"
    counting_store(store)
    cmd = [*AMRONET, "sweep", str(path), "--store", str(store), "--workers", "1", "--json", "-q"]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outs = [p.communicate(timeout=120) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    reports = [json.loads(out) for out, _ in outs]
    counts = recorded(store)
    assert len(counts) == 9 and all(n == 1 for *_, n in counts), f"a run was computed twice: {counts}"
    assert sum(r["done_now"] for r in reports) == 9
    assert all(r["done_now"] + r["finished_elsewhere"] + r["already_in_store"] == 9 for r in reports)
    assert sqlite3.connect(store).execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


def test_a_sweep_takes_over_the_runs_claimed_by_a_killed_sweep(tmp_path, capsys):
    path = write_sweep(tmp_path / "sweep.yaml", slow_sweep("takeover"))
    store = tmp_path / "k.sqlite"
    counting_store(store)
    cmd = [*AMRONET, "sweep", str(path), "--store", str(store), "--workers", "1", "--json", "-q"]
    first = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        assert wait_until(lambda: runs_in(store) >= 1, 60)
    finally:
        kill_group(first)  # part-way: it holds claims on the runs it has not recorded, and its process is gone
    con = sqlite3.connect(store)
    finished = con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    stale = con.execute("SELECT COUNT(*) FROM claims WHERE pid = ?", (first.pid,)).fetchone()[0]
    con.close()
    assert finished >= 1 and stale >= 1 and finished + stale == 9
    assert main(cmd[3:]) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["already_in_store"], report["done_now"]) == (finished, 9 - finished)
    counts = recorded(store)
    assert len(counts) == 9 and all(n == 1 for *_, n in counts), f"a run was computed twice: {counts}"
    assert sqlite3.connect(store).execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


def test_claims_are_taken_once_and_stale_ones_taken_over(tmp_path):
    from amronet.sweeps.store import ClaimOwner

    sweep = sweep_from_spec(tiny_sweep(seeds=2))
    (p, s0), (_, s1) = sweep.runs()[:2]
    keys = [(p.hash, s0), (p.hash, s1)]
    me, rival = ClaimOwner.new(), ClaimOwner("rival", "elsewhere.example", 1)
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    with ResultStore(tmp_path / "c.sqlite") as store:
        seen = dict.fromkeys(keys)
        assert store.claim(keys, me, seen).claimed == keys
        assert store.claim(keys, me, seen).claimed == keys, "one's own claims are one's own"
        other = ClaimOwner.new()
        held = store.claim(keys, other, seen)
        assert held.claimed == [] and set(held.held) == set(keys) and f"pid {os.getpid()}" in held.held[keys[0]]
        store.release(me)
        assert store.claim(keys, other, seen).claimed == keys
        store.release(other)

        def plant(owner, heartbeat):
            store.conn.execute("INSERT OR REPLACE INTO claims VALUES (?, ?, ?, ?, ?, 'then', ?)",
                               (*keys[0], owner.token, owner.host, owner.pid, heartbeat))

        plant(rival, time.time())  # another host, live heartbeat: held
        assert keys[0] in store.claim(keys[:1], me, seen).held
        plant(rival, time.time() - 120)  # its heartbeat is older than the lease: stale
        assert store.claim(keys[:1], me, seen).claimed == keys[:1]
        plant(ClaimOwner("gone", me.host, int(dead.stdout)), time.time())  # this host, its process is gone: stale
        assert store.claim(keys[:1], other, seen).claimed == keys[:1]

        outcome = execute_job({"scenario": p.scenario, "seed": s0})
        store.record(p.hash, s0, p.scenario, outcome)  # recording drops the run's claim
        assert store.conn.execute("SELECT COUNT(*) FROM claims WHERE seed = ?", (s0,)).fetchone()[0] == 0
        result = store.claim(keys, me, seen)
        assert result.finished == {keys[0]: "done"} and result.claimed == keys[1:]


def test_a_store_from_before_claims_opens_and_gains_the_table(tmp_path):
    path = tmp_path / "old.sqlite"
    ResultStore(path).close()
    con = sqlite3.connect(path)
    con.execute("DROP TABLE claims")  # as written by amronet before claims
    con.commit()
    con.close()
    with ResultStore(path, must_exist=True) as store:  # reading does not write
        assert store.sweeps() == []
    assert sqlite3.connect(path).execute("SELECT name FROM sqlite_master WHERE name = 'claims'").fetchone() is None
    spec = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(spec), "--store", str(path), "--workers", "1", "-q"]) == 0
    con = sqlite3.connect(path)
    assert con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 4
    assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0


# -- creating one store at the same instant -------------------------------------------------------------------------
def _create(path, barrier, results):
    barrier.wait()
    try:
        with ResultStore(path) as store:
            store.add_sweep("race", {"n": 1}, [])
        results.put("ok")
    except Exception as exc:
        results.put(f"{type(exc).__name__}: {exc}")


def test_twenty_processes_creating_one_store_at_once_all_succeed(tmp_path):
    ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
    n = 20
    for trial in range(3):
        path = tmp_path / f"new{trial}" / "results.sqlite"
        barrier, results = ctx.Barrier(n), ctx.Queue()
        procs = [ctx.Process(target=_create, args=(path, barrier, results)) for _ in range(n)]
        for proc in procs:
            proc.start()
        outcomes = [results.get(timeout=60) for _ in range(n)]
        for proc in procs:
            proc.join(timeout=60)
        assert outcomes == ["ok"] * n, sorted(set(outcomes))
        con = sqlite3.connect(path)
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        assert con.execute("PRAGMA application_id").fetchone()[0] == 0x414D524E
        assert con.execute("SELECT COUNT(*) FROM sweeps").fetchone()[0] == 1
        con.close()
        with ResultStore(path, must_exist=True) as store:
            assert [s["name"] for s in store.sweeps()] == ["race"]
