"""Ctrl-C during a sweep: it stops within a second or two, keeps every finished run, says what it dropped.

* ``amronet sweep`` interrupted while runs are in progress exits with 130 within a few seconds (it used to wait for
  the running jobs), leaves no process behind, prints one line counting the runs stored, dropped and not started,
  and running it again computes exactly the missing runs.
* A batch's runs reach the sweep's process one by one as each finishes, not when the whole batch ends: the loop's
  ``on_result``, the worker's reports, the local pool's channel.
* The workers of a local pool or of a ``LocalCluster`` ignore ``SIGINT`` (the sweep stops them); an executor that
  does not report (Dask) still gets honest counts, and an interrupted ``LocalCluster`` closes within a second or so.
* A worker that dies half-way through a report makes the pool raise ``WorkerDiedError``, it does not hang it.
* Ctrl-C of runs in the sweep's own process (``--workers 1``) never crashes it: a ``SIGINT`` landing in a numba
  kernel used to end it with a segmentation fault.
"""

import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time

import pytest

from amronet.cli import main
from amronet.scenario import load_scenario
from amronet.sim.batch import BatchSimulation
from amronet.sweeps import ResultStore, run_sweep, sweep_from_spec
from amronet.sweeps.executors import LocalExecutor
from amronet.sweeps.interrupt import SweepInterrupted
from amronet.sweeps.worker import execute_batch, reporting_to
from sweep_helpers import runs_in, session, tiny_sweep, write_sweep

LINUX = sys.platform.startswith("linux")
EXIT_BOUND_S = 4.0
"""Seconds from SIGINT to exit: generous for a loaded machine; a long run below takes longer than this."""


def short_and_long(name, long=(200000.0,)):
    """A short run (a fraction of a second), then long ones (several seconds each, more on a loaded machine)."""
    return {"name": name, "base": "self-spreading-6x6",
            "overrides": {"sim.stop_when_settled": False, "sim.record_every": 100},
            "grid": {"sim.time_limit": [20.0, *long]}, "seeds": 1}



def stored(store):
    con = sqlite3.connect(store)
    try:
        return dict(con.execute("SELECT scenario_hash || ':' || seed, wall_time_s FROM runs"))
    finally:
        con.close()


@pytest.mark.skipif(not LINUX, reason="finds the sweep's processes through /proc")
def test_ctrl_c_stops_at_once_keeps_the_finished_runs_and_resumes(tmp_path):
    path = write_sweep(tmp_path / "sweep.yaml", short_and_long("interrupted"))
    store = tmp_path / "i.sqlite"
    cmd = [sys.executable, "-m", "amronet.cli", "sweep", str(path), "--store", str(store), "--workers", "2", "-q"]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        # up to a few minutes where the kernels' cache is cold (the sweep compiles them first)
        deadline = time.monotonic() + 240
        while runs_in(store) < 1 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert runs_in(store) == 1, "the short run should be in, the long one running"
        sent = time.monotonic()
        os.kill(proc.pid, signal.SIGINT)  # as `kill -INT`; a terminal's Ctrl-C reaches the workers too
        proc.wait(timeout=60)
        took = time.monotonic() - sent
        left = session(proc.pid)
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
    err = proc.stderr.read().decode()
    assert proc.returncode == 130, err
    assert took < EXIT_BOUND_S, f"{took:.1f} s from SIGINT to exit"
    assert left == [], f"processes left behind: {left}"
    assert err.strip().splitlines()[-1] == (
        f"amronet: interrupted: 1 of 2 runs finished and stored in {store}, 1 in progress discarded, 0 not started; "
        "run the same command again to resume")
    survived = stored(store)
    assert len(survived) == 1
    assert sqlite3.connect(store).execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0

    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "-q"]) == 0
    after = stored(store)
    assert len(after) == 2
    assert all(after[k] == wall for k, wall in survived.items()), "a finished run was run again"


def test_ctrl_c_in_a_sweep_counts_the_runs_stored_dropped_and_not_started(tmp_path):
    import _thread
    import threading

    store = tmp_path / "r.sqlite"
    sweep = sweep_from_spec(short_and_long("counted", long=(200000.0, 200001.0, 200002.0)))
    sent = []

    def interrupt_after_the_first_run():
        while runs_in(store) < 1:
            time.sleep(0.01)
        time.sleep(0.5)  # the second long run starts on the worker the short one freed
        sent.append(time.monotonic())
        _thread.interrupt_main()

    threading.Thread(target=interrupt_after_the_first_run, daemon=True).start()
    with LocalExecutor(2) as ex, pytest.raises(KeyboardInterrupt) as info:
        run_sweep(sweep, store, ex, show_progress=False)
    took = time.monotonic() - sent[0]
    assert isinstance(info.value, SweepInterrupted), "a bare KeyboardInterrupt says nothing of the store"
    assert str(info.value) == (f"interrupted: 1 of 4 runs finished and stored in {store}, 2 in progress discarded, "
                               "1 not started; run the same command again to resume")
    assert took < EXIT_BOUND_S
    assert ex.started == 0, "the interrupted pool was stopped"


def test_a_batch_hands_over_each_run_as_it_stops():
    scenario = load_scenario("self-spreading-6x6", {"sim.time_limit": 250.0})
    sim = BatchSimulation(scenario, [0, 6])  # seed 6 settles at 228.2 s; seed 0 runs to the time limit
    seen = []
    results = sim.run(lambda k, result: seen.append((k, sim.steps, result)))
    assert [k for k, _, _ in seen] == [1, 0]
    assert all(result is results[k] for k, _, result in seen)
    assert seen[0][1] < seen[1][1], "the run that stopped first is handed over before the batch ends"


def test_a_worker_reports_each_run_and_returns_none_for_it():
    doc = sweep_from_spec(tiny_sweep(seeds=3)).points[0].scenario
    plain = execute_batch({"scenario": doc, "seeds": [0, 1, 2]})
    reports = []
    with reporting_to(reports.append):
        returned = execute_batch({"scenario": doc, "seeds": [0, 1, 2]})
    assert returned == [None, None, None]
    assert sorted(k for k, _ in reports) == [0, 1, 2]
    for k, outcome in reports:
        assert outcome["summary"] == plain[k]["summary"] and outcome["status"] == "done"


def _slow_abs(x):
    time.sleep(0.5)
    return abs(x)


def test_pool_workers_ignore_sigint_and_report_through_the_channel():
    from amronet.sweeps.worker import STARTED

    doc = sweep_from_spec(tiny_sweep(seeds=2)).points[0].scenario
    with LocalExecutor(2) as ex:
        reports = []
        out = dict(ex.imap_unordered(execute_batch, [{"scenario": doc, "seeds": [0, 1]}] * 2,
                                     on_report=lambda k, item: reports.append((k, item))))
        assert out == {0: [None, None], 1: [None, None]}
        assert sorted(k for k, item in reports if item == STARTED) == [0, 1]
        assert sorted((k, item[0]) for k, item in reports if item != STARTED) == [(0, 0), (0, 1), (1, 0), (1, 1)]
        results = ex.imap_unordered(_slow_abs, [-1, -2])
        first = next(results)
        for pid in ex._pool.pids():
            os.kill(pid, signal.SIGINT)
        assert sorted([first, *results]) == [(0, 1), (1, 2)]


def _dies_mid_report(_):
    """A job whose worker dies half-way through writing a report (as if killed by the out-of-memory killer)."""
    from amronet.sweeps import worker

    connection, _ = worker._outbox
    os.write(connection.fileno(), worker.FRAME.pack(1000) + b"cut short")
    os._exit(3)


def test_a_worker_dying_half_way_through_a_report_is_one_error_not_a_hang():
    import threading

    from amronet.sweeps.executors import WorkerDiedError

    raised = []

    def run():
        with LocalExecutor(2) as ex:
            try:
                list(ex.imap_unordered(_dies_mid_report, [0, 1], on_report=lambda k, item: None))
            except WorkerDiedError as exc:
                raised.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(30)
    assert not thread.is_alive(), "the pool hangs on a report cut short"
    assert len(raised) == 1


IN_PROCESS = textwrap.dedent("""
    import sys
    from amronet.sweeps import sweep_from_spec
    from amronet.sweeps.executors import LocalExecutor
    from amronet.sweeps.worker import execute_batch

    spec = {"name": "in-process", "base": "self-spreading-autolab", "overrides": {"sim.time_limit": 100000.0},
            "seeds": 1}
    job = {"scenario": sweep_from_spec(spec).points[0].scenario, "seeds": [0, 1, 2, 3]}
    with LocalExecutor(1) as ex:
        for _ in range(3):
            try:
                print("running", flush=True)
                list(ex.imap_unordered(execute_batch, [job]))
            except KeyboardInterrupt:
                print("interrupted", flush=True)
""")


@pytest.mark.skipif(not LINUX, reason="the crash this guards against was seen on Linux")
def test_ctrl_c_of_runs_in_the_sweeps_own_process_never_crashes_it():
    # a SIGINT that lands in a numba kernel crashed the process (SIGSEGV) most times: with --workers 1 the runs
    # are in the sweep's own process
    proc = subprocess.Popen([sys.executable, "-c", IN_PROCESS], stdout=subprocess.PIPE, text=True)
    try:
        for _ in range(3):
            assert proc.stdout.readline() == "running\n"
            time.sleep(0.5)  # well into the batch's kernels
            proc.send_signal(signal.SIGINT)
            assert proc.stdout.readline() == "interrupted\n", f"exit status {proc.wait()}"
        assert proc.wait(timeout=30) == 0
    finally:
        proc.kill()
        proc.wait()


class _Interrupted:
    """An executor (like Dask: no reports) interrupted by Ctrl-C after its first job."""

    slots = 1

    def imap_unordered(self, fn, jobs):
        yield 0, fn(jobs[0])
        raise KeyboardInterrupt

    def describe(self):
        return "an interrupted executor"

    def close(self):
        pass


def test_an_interrupted_sweep_counts_from_the_store_without_reports(tmp_path):
    store = tmp_path / "r.sqlite"
    with pytest.raises(SweepInterrupted) as info:
        run_sweep(sweep_from_spec(tiny_sweep(radii=(0.8, 1.0, 1.2))), store, _Interrupted(), show_progress=False)
    # the first point's two seeds are one batch, done; the next batch was running (one slot), the third not
    assert str(info.value) == (f"interrupted: 2 of 6 runs finished and stored in {store}, 2 in progress discarded, "
                               "2 not started; run the same command again to resume")
    with ResultStore(store) as st:
        assert len(st.runs()) == 2


def test_ctrl_c_on_a_local_dask_cluster_is_counted_and_closes_it_at_once(tmp_path):
    import _thread
    import threading

    from amronet.sweeps import DaskExecutor

    store = tmp_path / "d.sqlite"
    sweep = sweep_from_spec(short_and_long("dask", long=(200000.0, 200001.0, 200002.0)))
    executor = DaskExecutor(workers=2)
    pids = sorted(executor.client.run(os.getpid).values())
    for pid in pids:  # a terminal's Ctrl-C reaches the cluster's workers too: they leave it to the sweep
        os.kill(pid, signal.SIGINT)
    time.sleep(0.5)
    assert sorted(executor.client.run(os.getpid).values()) == pids

    def interrupt_after_the_first_run():
        while runs_in(store) < 1:
            time.sleep(0.01)
        _thread.interrupt_main()

    threading.Thread(target=interrupt_after_the_first_run, daemon=True).start()
    try:
        with pytest.raises(KeyboardInterrupt) as info:
            run_sweep(sweep, store, executor, show_progress=False)
    finally:
        start = time.monotonic()
        executor.close()
        took = time.monotonic() - start
    # no reports from Dask: the first `slots` batches not finished count as in progress
    assert str(info.value) == (f"interrupted: 1 of 4 runs finished and stored in {store}, 2 in progress discarded, "
                               "1 not started; run the same command again to resume")
    assert took < 3.5, f"closing the interrupted LocalCluster took {took:.1f} s"
