"""A sweep killed with SIGKILL part-way and started again ends with exactly the rows of an uninterrupted one."""

import os
import signal
import sqlite3
import subprocess
import sys
import time

from amronet.cli import main
from sweep_helpers import runs_in, same_store_content, table_rows, write_sweep

SPEC = {"name": "killed", "base": "self-spreading-6x6", "overrides": {"sim.time_limit": 150.0},
        "grid": {"radio.r_c": [0.8, 1.0, 1.2]}, "seeds": 10}
TOTAL = 30


def test_sigkill_part_way_then_resume(tmp_path):
    path = write_sweep(tmp_path / "sweep.yaml", SPEC)
    store = tmp_path / "killed.sqlite"
    cmd = [sys.executable, "-m", "amronet.cli", "sweep", str(path), "--store", str(store), "--workers", "2", "-q"]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 60
    try:
        while runs_in(store) < 4 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its workers, like a power cut
        proc.wait()
    survived = {(h, s): wall for h, s, wall in sqlite3.connect(store).execute(
        "SELECT scenario_hash, seed, wall_time_s FROM runs")}
    assert 4 <= len(survived) < TOTAL, "the kill should land part-way"
    assert proc.returncode == -signal.SIGKILL

    assert main(["sweep", str(path), "--store", str(store), "--workers", "2", "-q"]) == 0
    assert main(["sweep", str(path), "--store", str(tmp_path / "clean.sqlite"), "--workers", "2", "-q"]) == 0
    keys = [(h, s) for h, s, *_ in table_rows(store, "runs")]
    assert len(keys) == len(set(keys)) == TOTAL
    assert same_store_content(store, tmp_path / "clean.sqlite")
    after = dict(sqlite3.connect(store).execute("SELECT scenario_hash || ':' || seed, wall_time_s FROM runs"))
    assert all(after[f"{h}:{s}"] == wall for (h, s), wall in survived.items()), "a finished run was run again"
