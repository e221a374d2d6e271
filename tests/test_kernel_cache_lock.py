"""Processes sharing amronet's kernel cache compile each kernel once between them (amronet.kernel_cache_lock)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from amronet import kernel_cache

pytest.importorskip("fcntl")

# A module of kernels, a caller and its callee; its body is long enough that numba takes a while to compile it.
_KERNELS = """
import amronet  # first: numba's cache is amronet's folder (a spawned worker imports this module first)
import numba
import numpy as np


@numba.njit(cache=True)
def leaf(x):
    return x * 2.0 + 1.0


@numba.njit(cache=True)
def total(a):
    s = 0.0
    for v in a:
        s += leaf(v)
{body}
    return s


@numba.njit(cache=True)
def other(a):
    return total(a) + leaf(a[0])


def task(k):
    # a worker's task: the kernels it compiles (numba's events), its process
    import os
    from numba.core import event

    compiled = []

    class Listener(event.Listener):
        def on_start(self, ev):
            compiled.append(ev.data["dispatcher"].py_func.__name__)

        def on_end(self, ev):
            pass

    with event.install_listener("numba:compile", Listener()):
        (total if k % 2 else other)(np.ones(3))
    return os.getpid(), compiled
"""

# What each process runs: amronet configures numba's cache before the kernels are defined; numba's compile events
# of the kernels above are listed, with when the process got its result.
_PRELUDE = """
import json, sys, time
import amronet
import numpy as np
from numba.core import event
compiled = []

class Listener(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__name__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Listener())
import lockkernels
from amronet import kernel_cache, kernel_cache_lock
"""

# Holds the lock of `total` (as a process compiling it would) until the other process is about to call it, then
# some more seconds (or, with "hold", until the other process has its result), then compiles it and lets go.
_HOLDER = _PRELUDE + """
import numba
from pathlib import Path
path = kernel_cache_lock.lock_path(lockkernels.total, (numba.typeof(np.ones(3)),))
with kernel_cache_lock._locked(path):
    Path(sys.argv[1], "holding").write_text(str(path))
    while not Path(sys.argv[1], "calling").exists():
        time.sleep(0.01)
    if sys.argv[3] == "compile":
        time.sleep(float(sys.argv[2]))
        lockkernels.total(np.ones(3))
    else:
        deadline = time.time() + float(sys.argv[2])
        while not Path(sys.argv[1], "done").exists() and time.time() < deadline:
            time.sleep(0.01)
    released = time.time()
print(json.dumps({"compiled": compiled, "released": released, "lock": str(path)}))
"""

_CALLER = _PRELUDE + """
from pathlib import Path
kernel_cache_lock.PATIENCE = float(sys.argv[2])
Path(sys.argv[1], "calling").touch()
t = time.time()
lockkernels.total(np.ones(3))
done = time.time()
Path(sys.argv[1], "done").touch()
print(json.dumps({"compiled": compiled, "done": done, "waited": done - t}))
"""


def _setup(tmp_path: Path) -> dict[str, str]:
    body = "\n".join(f"    s = s * 0.5 + leaf(s + {k}.0) * 0.25" for k in range(60))
    (tmp_path / "lockkernels.py").write_text(_KERNELS.format(body=body))
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    return env


def _start(code: str, env: dict[str, str], *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _result(proc: subprocess.Popen[str]) -> dict:
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err[-3000:]
    return json.loads(out.strip().splitlines()[-1])


def _wait_for(path: Path, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 240
    while not path.exists():
        assert proc.poll() is None, proc.communicate()[1][-3000:]
        assert time.monotonic() < deadline, f"{path.name} never came"
        time.sleep(0.02)


def test_a_process_waits_for_the_one_compiling_a_kernel_and_loads_it(tmp_path):
    env = _setup(tmp_path)
    holder = _start(_HOLDER, env, tmp_path, 2.0, "compile")
    _wait_for(tmp_path / "holding", holder)
    caller = _start(_CALLER, env, tmp_path, 300.0)
    held, called = _result(holder), _result(caller)
    assert held["compiled"] == ["total", "leaf"]
    assert called["compiled"] == []  # loaded what the holder saved, compiled nothing
    assert called["done"] >= held["released"]
    assert Path(held["lock"]).parent == kernel_cache.cache_folder(tmp_path / "cache" / "amronet") / "locks"


def test_a_lock_held_too_long_is_given_up(tmp_path):
    env = _setup(tmp_path)
    holder = _start(_HOLDER, env, tmp_path, 240.0, "hold")
    _wait_for(tmp_path / "holding", holder)
    caller = _start(_CALLER, env, tmp_path, 0.5)
    called = _result(caller)
    assert sorted(called["compiled"]) == ["leaf", "total"]  # compiled by itself after 0.5 s: as numba alone
    held = _result(holder)
    assert called["done"] < held["released"]  # while the holder still held the lock


def test_the_users_own_cache_folder_is_locked_too(tmp_path):
    # NUMBA_CACHE_DIR (CI, containers): processes still compile each kernel once between them; the locks are in a
    # folder of amronet's own there, and nothing goes into amronet's folder of the user's cache home
    env = {**_setup(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "mine")}
    holder = _start(_HOLDER, env, tmp_path, 2.0, "compile")
    _wait_for(tmp_path / "holding", holder)
    caller = _start(_CALLER, env, tmp_path, 300.0)
    held, called = _result(holder), _result(caller)
    assert held["compiled"] == ["total", "leaf"]
    assert called["compiled"] == []  # waited, then loaded what the holder saved in the user's folder
    assert called["done"] >= held["released"]
    assert Path(held["lock"]).parent == tmp_path / "mine" / "amronet" / "locks"
    assert not (tmp_path / "cache").exists()


def test_a_folder_with_locks_is_still_amronets_to_prune(tmp_path):
    folder = tmp_path / "numba-0123456789abcdef"
    (folder / "locks").mkdir(parents=True)
    (folder / kernel_cache.STAMP).write_text(folder.name + "\n")
    (folder / "locks" / "kernels.step-12.py311.0123456789abcdef.lock").touch()
    assert kernel_cache._removable(folder)
    (folder / "locks" / "notes.txt").touch()
    assert not kernel_cache._removable(folder)


_POOL = """
import json, multiprocessing, sys
from concurrent.futures import ProcessPoolExecutor
import amronet
import lockkernels
with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn")) as pool:
    done = list(pool.map(lockkernels.task, range(4)))
print(json.dumps(done))
"""


def test_two_workers_compile_each_kernel_once_and_a_later_process_none(tmp_path):
    env = _setup(tmp_path)
    proc = subprocess.run([sys.executable, "-c", _POOL], env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    done = json.loads(proc.stdout.strip().splitlines()[-1])
    compiled = sorted(name for _, names in done for name in names)
    assert compiled == ["leaf", "other", "total"]  # each once, in one worker or the other
    code = _PRELUDE + "lockkernels.other(np.ones(3)); lockkernels.total(np.ones(3)); print(json.dumps(compiled))"
    later = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert later.returncode == 0, later.stderr[-3000:]
    assert json.loads(later.stdout.strip().splitlines()[-1]) == []  # all loaded from the cache
