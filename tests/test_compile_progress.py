"""``amronet compile`` says which kernel group compiles, how many are left and the seconds elapsed (on stderr)."""

from __future__ import annotations

import io
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import amronet.sim.warmup as warmup
from amronet.cli.compile import CompileProgress
from amronet.cli.main import main


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_one_line_per_group_as_it_starts_when_not_a_terminal():
    ticks = iter([100.0, 100.0, 101.4, 112.6])
    out = io.StringIO()
    with CompileProgress(3, out, live=False, clock=lambda: next(ticks)) as report:
        report.started("explorer frontier")
        report.started("signal map")
        report.finished("signal map", 1.4)
        report.started("walk growth")
        report.finished("explorer frontier", 12.6)
        report.finished("walk growth", 0.1)
    assert out.getvalue().splitlines() == [
        "[   0 s] compiling kernel group 1 of 3 (2 to go): explorer frontier",
        "[   1 s] compiling kernel group 2 of 3 (1 to go): signal map",
        "[  13 s] compiling kernel group 3 of 3 (0 to go): walk growth",
    ]
    assert report.done == 3 and report.running == []


def test_one_updating_line_on_a_terminal():
    out = _Terminal()
    with CompileProgress(2, out, live=True) as report:
        report.started("explorer frontier")
        report.started("signal map")
        report.finished("signal map", 1.0)
        shown = out.getvalue()
    assert "\n" not in shown  # one line, drawn again in place
    last = shown.split("\r")[-1]
    assert "compiling kernels" in last and "1/2" in last and "explorer frontier" in last and "signal" not in last


def test_compile_reports_each_group_on_stderr_and_quiet_only_the_end(monkeypatch, capsys):
    labels = ["explorer frontier", "signal map"]

    def fake_warm_up(jobs, started, progress, **kwargs):
        for label in labels:
            if started is not None:
                started(label)
            if progress is not None:
                progress(label, 0.5)
        return 1.0

    monkeypatch.setattr(warmup, "task_labels", lambda large=False: labels)
    monkeypatch.setattr(warmup, "warm_up", fake_warm_up)
    assert main(["compile", "--jobs", "1"]) == 0
    out, err = capsys.readouterr()
    assert err.splitlines() == ["[   0 s] compiling kernel group 1 of 2 (1 to go): explorer frontier",
                                "[   0 s] compiling kernel group 2 of 2 (0 to go): signal map"]
    assert out == ("amronet's kernels are compiled and cached (1.0 s): a first run no longer compiles (one of "
                   "30 000 robots or more: amronet compile --large-runs)\n")
    assert main(["compile", "--jobs", "1", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert err == "" and out.startswith("amronet's kernels are compiled and cached")


def test_the_pool_is_handed_a_group_only_when_a_worker_is_free():
    lock = threading.Lock()
    running: set[str] = set()
    events: list[tuple[str, str, int]] = []
    labels = [f"group {k}" for k in range(7)]

    def started(label):
        with lock:
            running.add(label)
            events.append(("start", label, len(running)))

    def progress(label, seconds):
        with lock:
            running.discard(label)
            events.append(("end", label, len(running)))

    def run(k):
        time.sleep(0.01 * (k % 3))
        return float(k)

    with ThreadPoolExecutor(max_workers=4) as pool:  # more threads than slots: the scheduler holds the rest back
        warmup.run_in_pool(pool, [(label, k) for k, label in enumerate(labels)], 2, run, started, progress)
    starts = [label for kind, label, _ in events if kind == "start"]
    assert starts == labels  # in order
    assert max(n for kind, _, n in events if kind == "start") == 2
    assert sorted(label for kind, label, _ in events if kind == "end") == sorted(labels) and running == set()


def test_one_job_reports_each_case_as_it_starts_and_ends(monkeypatch):
    events: list[str] = []
    monkeypatch.setattr(warmup, "_run_case", lambda k: events.append(f"run {k}") or 0.0)
    monkeypatch.setattr(warmup, "mark_compiled", lambda name: None)
    keys = dict(warmup._tasks())
    warmup.warm_up(only=["walk growth", "signal map"], started=lambda label: events.append(f"start {label}"),
                   progress=lambda label, s: events.append(f"end {label}"))
    assert events == ["start signal map", f"run {keys['signal map']}", "end signal map",
                      "start walk growth", f"run {keys['walk growth']}", "end walk growth"]
    assert warmup.task_labels() == [label for label, _ in warmup._tasks()]


def test_a_failed_group_is_one_line_and_a_nonzero_exit(monkeypatch, capsys):
    noted: list[str] = []
    monkeypatch.setattr(warmup, "mark_compiled", noted.append)
    # no such case: the worker raises
    monkeypatch.setattr(warmup, "_tasks", lambda large=False: [("broken group", 10**6)])
    assert main(["compile", "--jobs", "2"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == ("amronet: error: kernel group 'broken group' failed (IndexError: list index out of range); "
                       "runs still work and compile the kernels they use")
    assert not any("Traceback" in line for line in err) and noted == []


def test_a_failed_group_in_this_process_names_its_first_line_only(monkeypatch, capsys):
    def broken(k):
        raise RuntimeError("the kernel did not type\nmore lines of numba's message")

    monkeypatch.setattr(warmup, "_run_case", broken)
    monkeypatch.setattr(warmup, "_tasks", lambda large=False: [("signal map", -1)])
    assert main(["compile", "--jobs", "1", "--quiet"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err == ("amronet: error: kernel group 'signal map' failed (RuntimeError: the kernel did not "
                                 "type); runs still work and compile the kernels they use\n")


def test_a_group_of_an_algorithm_already_running_waits_for_one_of_another():
    lock = threading.Lock()
    starts: list[tuple[str, set[str]]] = []
    running: set[str] = set()
    tasks = [("frontier", 0), ("agents random", 1), ("agents wall", 2), ("dssa", 3), ("field", 4), ("field batch", 5)]
    groups = {0: "agents", 1: "agents", 2: "agents", 3: "dssa", 4: "field", 5: "field"}

    def started(label):
        with lock:
            starts.append((label, set(running)))
            running.add(label)

    def progress(label, seconds):
        with lock:
            running.discard(label)

    def run(k):
        time.sleep(0.5 if k == 0 else 0.02)  # the long chain: the others run meanwhile
        return 0.0

    with ThreadPoolExecutor(max_workers=2) as pool:
        warmup.run_in_pool(pool, tasks, 2, run, started, progress, group=groups.__getitem__)
    # not the agents' while frontier runs, as long as another group's is left; then them rather than nothing
    assert [label for label, _ in starts] == ["frontier", "dssa", "field", "field batch", "agents random",
                                              "agents wall"]
    assert ("field", {"frontier"}) in starts and running == set()


def test_the_kernels_of_large_runs_compile_only_when_asked():
    large = [case.label for case in warmup.warmup_cases() if case.threaded]
    assert large  # self-spreading's threaded kernels
    assert not set(large) & set(warmup.task_labels())
    assert set(large) <= set(warmup.task_labels(large=True))
    assert set(warmup.task_labels(large=True)) - set(warmup.task_labels()) == set(large)


def test_compile_large_runs_passes_it_on(monkeypatch, capsys):
    calls = []
    monkeypatch.setattr(warmup, "warm_up", lambda **kw: calls.append(kw["large"]) or 1.0)
    assert main(["compile", "--jobs", "1", "--quiet", "--large-runs"]) == 0
    assert capsys.readouterr().out == ("amronet's kernels are compiled and cached (1.0 s): a first run no longer "
                                       "compiles\n")
    assert main(["compile", "--jobs", "1", "--quiet"]) == 0
    assert calls == [True, False]
