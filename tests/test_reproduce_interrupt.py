"""Ctrl-C of ``amronet reproduce`` (any figure) and of its kernels' warm-up: exit 130, no process left, one line.

* The warm-up that compiles the kernels before a figure's first runs (a cold cache) ends its workers at once on
  Ctrl-C; it used to wait for their compiles (seconds to tens of seconds), and they printed tracebacks.
* A ``KeyboardInterrupt`` that a library turns into an error of its own (numba, stopped mid-compile, raised
  ``RuntimeError: no compiled object yet``) still ends the command with 130 and one line, not a traceback.
"""

import importlib
import os
import signal
import sys
import threading
import time

import pytest

from amronet.cli import main
from amronet.sim import warmup

cli_main = importlib.import_module("amronet.cli.main")  # (``amronet.cli.main`` is also its function)


def _cases_take_a_minute():
    """A warm-up worker's initializer (in the worker): every case takes a minute, like a long compile."""
    warmup._run_case = lambda k: time.sleep(60) or 60.0


def _children_of(pid):
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat", "rb") as f:
                    fields = f.read().rsplit(b")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry))
    return out


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="lists the workers through /proc")
def test_ctrl_c_ends_the_warm_ups_workers_at_once(monkeypatch):
    monkeypatch.setattr(warmup, "_tasks", lambda large=False: [("first", 0), ("second", 1)])
    started, sent = threading.Event(), []

    def ctrl_c_once_both_compile():
        started.wait(120)
        time.sleep(1.0)
        sent.append(time.monotonic())
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)  # Ctrl-C, where it wakes a wait up

    threading.Thread(target=ctrl_c_once_both_compile, daemon=True).start()
    with pytest.raises(KeyboardInterrupt):
        warmup.warm_up(jobs=2, initializer=_cases_take_a_minute, started=lambda label: started.set())
    took = time.monotonic() - sent[0]
    assert took < 5.0, f"{took:.1f} s to end the workers"
    assert [pid for pid in _children_of(os.getpid()) if os.path.exists(f"/proc/{pid}")
            and b"resource_tracker" not in open(f"/proc/{pid}/cmdline", "rb").read()] == []


def test_ctrl_c_turned_into_another_error_by_a_library_is_still_an_interruption(monkeypatch, tmp_path, capsys):
    def compiling(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise RuntimeError("no compiled object yet for <Library '_upper_pairs'>") from None

    monkeypatch.setattr(cli_main, "_cmd_reproduce", compiling)
    assert main(["reproduce", "fig11", "--quick", "--out", str(tmp_path / "out")]) == 130
    assert capsys.readouterr().err == "amronet: interrupted; nothing was written\n"
    assert not (tmp_path / "out").exists()


def test_other_errors_are_not_taken_for_an_interruption(monkeypatch, tmp_path):
    def failing(args):
        raise RuntimeError("a bug")

    monkeypatch.setattr(cli_main, "_cmd_reproduce", failing)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["reproduce", "fig11", "--quick", "--out", str(tmp_path / "out")])
