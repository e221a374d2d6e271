"""Shared pieces of the sweep, store, Dask and planner tests: tiny sweeps and store comparisons."""

import sqlite3
from pathlib import Path

import yaml

WALL_TIME = {"wall_time_s", "finished_at", "created"}


def tiny_sweep(name="tiny", time_limit=3.0, radii=(0.8, 1.0), seeds=2, **extra):
    """A sweep of short self-spreading runs on the 6 m x 6 m field (each a few milliseconds)."""
    spec = {"name": name, "base": "self-spreading-6x6", "overrides": {"sim.time_limit": time_limit},
            "grid": {"radio.r_c": list(radii)}, "seeds": seeds}
    spec.update(extra)
    return spec


def write_sweep(path: Path, spec) -> Path:
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def table_rows(store: Path, table: str):
    """Every row of a store's table as sorted tuples, without the wall-time columns."""
    con = sqlite3.connect(store)
    try:
        cols = [r[1] for r in con.execute(f"PRAGMA table_info({table})") if r[1] not in WALL_TIME]
        rows = con.execute(f"SELECT {', '.join(cols)} FROM {table}").fetchall()
    finally:
        con.close()
    return sorted(rows, key=repr)


def same_store_content(a: Path, b: Path, tables=("runs", "timeseries", "sweep_runs", "sweeps")) -> bool:
    return all(table_rows(a, t) == table_rows(b, t) for t in tables)


def runs_in(store: Path) -> int:
    """How many runs a store holds right now, read-only (0 while it does not exist or is locked)."""
    try:
        con = sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=0.2)
        try:
            return con.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
        finally:
            con.close()
    except sqlite3.Error:
        return 0


def proc_stats() -> dict[int, list[bytes]]:
    """Each live process's ``/proc/PID/stat`` fields after the command name (state, ppid, pgrp, session, ...)."""
    out = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                out[int(entry.name)] = (entry / "stat").read_bytes().rsplit(b")", 1)[1].split()
            except (OSError, IndexError):
                continue
    return out


def children(pid):
    """Pids of the processes whose parent is ``pid``."""
    return [p for p, fields in proc_stats().items() if int(fields[1]) == pid]


def session(sid):
    """Pids of the live (not zombie) processes of session ``sid``."""
    return [p for p, fields in proc_stats().items() if int(fields[3]) == sid and fields[0] not in (b"Z", b"X")]
