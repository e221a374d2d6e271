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

    monkeypatch.setattr(warmup, "task_labels", lambda: labels)
    monkeypatch.setattr(warmup, "warm_up", fake_warm_up)
    assert main(["compile", "--jobs", "1"]) == 0
    out, err = capsys.readouterr()
    assert err.splitlines() == ["[   0 s] compiling kernel group 1 of 2 (1 to go): explorer frontier",
                                "[   0 s] compiling kernel group 2 of 2 (0 to go): signal map"]
    assert out == "amronet's kernels are compiled and cached (1.0 s): a first run no longer compiles\n"
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
