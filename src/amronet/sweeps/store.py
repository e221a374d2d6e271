"""The result store: one SQLite file (WAL mode) that never loses a finished run.

Tables:

* ``runs`` — one row per (``scenario_hash``, ``seed``): the resolved scenario (canonical JSON), ``status``
  (``done`` or ``failed``), the one-line ``error`` of a failed run, the ``summary`` (JSON, without the fields
  kept in columns), the main metrics as columns (``nodes_total``, ``routers_deployed``, ``coverage``,
  ``connected_coverage``, ``stop_reason``, ``sim_time_s``), ``amronet_version``, ``host``, and the wall-time
  columns ``wall_time_s`` and ``finished_at``.
* ``timeseries`` — one row per recorded step of a done run (``k`` = 0, 1, ...): ``t``, ``coverage``,
  ``connected_coverage``, ``routers_deployed``, ``components``, ``agents_connected``.
* ``sweeps`` — ``id``, ``name``, ``spec`` (canonical JSON), ``spec_hash`` (unique), ``created``.
* ``sweep_runs`` — which runs belong to which sweep, at which ``point``, with the point's ``labels`` (JSON: the
  swept keys' values, or a figure's labels). A run belongs to every sweep that contains it.

Every finished run is written in one transaction with ``synchronous = FULL``: after a crash (``SIGKILL``, power
loss) the file holds every run whose transaction committed and nothing of the others, so running the sweep
again completes exactly the missing ones. Only one process (the parent of the workers) writes.

A path that exists but is not an amronet store (another SQLite database, a text file) is refused before it is
opened, so it is left byte for byte as it was.
"""

from __future__ import annotations

import json
import re
import sqlite3
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError
from amronet.sweeps.identity import canonical_json
from amronet.sweeps.worker import SUMMARY_EXTRAS

__all__ = ["APPLICATION_ID", "METRIC_COLUMNS", "ResultStore", "StoreError"]

APPLICATION_ID = 0x414D524E
"""SQLite ``application_id`` of an amronet result store ("AMRN")."""
SCHEMA_VERSION = 1
METRIC_COLUMNS = ("nodes_total", "routers_deployed", "coverage", "connected_coverage", "stop_reason", "sim_time_s")
"""Summary fields copied into columns of ``runs``."""
TIMESERIES_COLUMNS = ("t", "coverage", "connected_coverage", "routers_deployed", "components", "agents_connected")
WALL_TIME_COLUMNS = ("wall_time_s", "finished_at", "created")
"""Columns that differ between two otherwise identical sweeps."""

_MAGIC = b"SQLite format 3\x00"
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

_SCHEMA = f"""
CREATE TABLE sweeps (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL,
    spec TEXT NOT NULL,
    spec_hash TEXT NOT NULL UNIQUE,
    created TEXT NOT NULL
);
CREATE TABLE runs (
    scenario_hash TEXT NOT NULL,
    seed INTEGER NOT NULL,
    scenario TEXT NOT NULL,
    status TEXT NOT NULL CHECK (status IN ('done', 'failed')),
    error TEXT,
    summary TEXT,
    nodes_total INTEGER,
    routers_deployed INTEGER,
    coverage REAL,
    connected_coverage REAL,
    stop_reason TEXT,
    sim_time_s REAL,
    timeseries_columns TEXT,
    amronet_version TEXT NOT NULL,
    host TEXT,
    wall_time_s REAL,
    finished_at TEXT NOT NULL,
    PRIMARY KEY (scenario_hash, seed)
) WITHOUT ROWID;
CREATE TABLE sweep_runs (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id),
    scenario_hash TEXT NOT NULL,
    seed INTEGER NOT NULL,
    point INTEGER NOT NULL,
    labels TEXT NOT NULL,
    PRIMARY KEY (sweep_id, scenario_hash, seed)
) WITHOUT ROWID;
CREATE TABLE timeseries (
    scenario_hash TEXT NOT NULL,
    seed INTEGER NOT NULL,
    k INTEGER NOT NULL,
    t REAL NOT NULL,
    coverage REAL,
    connected_coverage REAL,
    routers_deployed INTEGER,
    components INTEGER,
    agents_connected REAL,
    PRIMARY KEY (scenario_hash, seed, k)
) WITHOUT ROWID;
PRAGMA application_id = {APPLICATION_ID};
PRAGMA user_version = {SCHEMA_VERSION};
"""


class StoreError(AmronetError):
    """The result store cannot be used (not a store, unreadable, a newer schema)."""


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def check_store_path(path: Path, must_exist: bool = False, option: str = "--store") -> bool:
    """Check that ``path`` is an amronet store or can become one, without opening it.

    Args:
        path: The store's file.
        must_exist: Refuse a path with no store.
        option: How errors name the path: the ``--store`` option, or ``STORE`` where it is a positional argument.

    Returns:
        ``True`` when the store already exists (a non-empty file).

    Raises:
        StoreError: The path is a folder, not a SQLite database, or another application's database; or
            ``must_exist`` and there is no store.
    """
    shown = str(path)
    if path.is_dir():
        raise StoreError(f"{option}: {shown!r} is a folder; give a file name such as results.sqlite")
    if not path.exists() or path.stat().st_size == 0:
        wal = Path(f"{path}-wal")
        if wal.exists() and wal.stat().st_size > 0:
            return True  # created, then killed before the first checkpoint: SQLite recovers it from the WAL
        if must_exist:
            raise StoreError(f"{option}: no result store at {shown!r}; run `amronet sweep ... --store {shown}` first")
        return False
    try:
        with open(path, "rb") as fh:
            head = fh.read(100)
    except OSError as exc:
        raise StoreError(f"{option}: cannot read {shown!r}: {exc.strerror}") from None
    if len(head) < 100 or head[:16] != _MAGIC:
        raise StoreError(f"{option}: {shown!r} is not a SQLite database; give a new file name or an amronet store")
    if int.from_bytes(head[68:72], "big") != APPLICATION_ID:
        raise StoreError(f"{option}: {shown!r} is a SQLite database but not an amronet result store; "
                         "give a new file name")
    return True


class ResultStore:
    """An open result store (see the module docstring).

    Args:
        path: The SQLite file; created (with its folder) unless ``must_exist``.
        must_exist: Refuse to create a new store (for reading).
        option: How errors name the path (``--store``, or ``STORE`` for ``amronet results`` and ``plot``).

    Raises:
        StoreError: See :func:`check_store_path`; or the file is damaged or from a newer amronet.
    """

    def __init__(self, path: str | Path, must_exist: bool = False, option: str = "--store") -> None:
        self.path = Path(path)
        exists = check_store_path(self.path, must_exist=must_exist, option=option)
        try:
            if not exists:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            self.conn = sqlite3.connect(self.path, isolation_level=None, timeout=60.0)
        except (OSError, sqlite3.Error) as exc:
            raise StoreError(f"{option}: cannot open {str(self.path)!r}: {exc}") from None
        try:
            self.conn.execute("PRAGMA busy_timeout = 60000")
            if not exists:
                # created in rollback-journal mode, so the header with the application id reaches the main file
                self.conn.executescript("BEGIN IMMEDIATE;" + _SCHEMA + "COMMIT;")
            else:
                version = self.conn.execute("PRAGMA user_version").fetchone()[0]
                if version > SCHEMA_VERSION:
                    raise StoreError(f"{option}: {str(self.path)!r} was written by a newer amronet "
                                     f"(schema {version}); upgrade amronet")
            self.conn.execute("PRAGMA journal_mode = WAL")
            self.conn.execute("PRAGMA synchronous = FULL")
            self._ts_columns = [r[1] for r in self.conn.execute("PRAGMA table_info(timeseries)")]
        except sqlite3.DatabaseError as exc:
            self.conn.close()
            raise StoreError(f"{option}: {str(self.path)!r} is damaged or not a result store: {exc}") from None

    # -- plumbing --------------------------------------------------------------------------------------------
    def close(self) -> None:
        """Close the store (the WAL is checkpointed into the main file)."""
        self.conn.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        self.conn.execute("BEGIN IMMEDIATE")
        try:
            yield self.conn
        except BaseException:
            self.conn.execute("ROLLBACK")
            raise
        self.conn.execute("COMMIT")

    # -- sweeps ----------------------------------------------------------------------------------------------
    def add_sweep(self, name: str, spec: dict[str, Any], links: Iterable[tuple[str, int, int, dict[str, Any]]]) -> int:
        """Register a sweep (or find the identical one) and link its runs, in one transaction.

        Args:
            name: The sweep's name.
            spec: Its specification (stored as canonical JSON; identical specs are one sweep).
            links: ``(scenario_hash, seed, point, labels)`` of every run of the sweep.

        Returns:
            The sweep's id.
        """
        import hashlib

        text = canonical_json(spec)
        digest = hashlib.sha256(text.encode()).hexdigest()
        with self._transaction() as c:
            c.execute("INSERT OR IGNORE INTO sweeps (name, spec, spec_hash, created) VALUES (?, ?, ?, ?)",
                      (name, text, digest, _now()))
            sweep_id = c.execute("SELECT id FROM sweeps WHERE spec_hash = ?", (digest,)).fetchone()[0]
            c.executemany("INSERT OR IGNORE INTO sweep_runs (sweep_id, scenario_hash, seed, point, labels) "
                          "VALUES (?, ?, ?, ?, ?)",
                          [(sweep_id, h, s, p, canonical_json(lab)) for h, s, p, lab in links])
        return int(sweep_id)

    def sweeps(self) -> list[dict[str, Any]]:
        """Every sweep with its run counts: ``id, name, created, runs, done, failed, missing``."""
        rows = self.conn.execute(
            "SELECT s.id, s.name, s.created, COUNT(l.seed), "
            "SUM(CASE WHEN r.status = 'done' THEN 1 ELSE 0 END), "
            "SUM(CASE WHEN r.status = 'failed' THEN 1 ELSE 0 END) "
            "FROM sweeps s LEFT JOIN sweep_runs l ON l.sweep_id = s.id "
            "LEFT JOIN runs r ON r.scenario_hash = l.scenario_hash AND r.seed = l.seed "
            "GROUP BY s.id ORDER BY s.id").fetchall()
        return [{"id": i, "name": n, "created": c, "runs": t, "done": d or 0, "failed": f or 0,
                 "missing": t - (d or 0) - (f or 0)} for i, n, c, t, d, f in rows]

    def find_sweep(self, name_or_id: str) -> int:
        """The id of the sweep with this name (the latest of that name) or id.

        Raises:
            StoreError: No such sweep.
        """
        if name_or_id.isdigit():
            row = self.conn.execute("SELECT id FROM sweeps WHERE id = ?", (int(name_or_id),)).fetchone()
        else:
            row = self.conn.execute("SELECT id FROM sweeps WHERE name = ? ORDER BY id DESC", (name_or_id,)).fetchone()
        if row is None:
            names = ", ".join(f"{s['id']}:{s['name']}" for s in self.sweeps()) or "none"
            raise StoreError(f"--sweep: no sweep {name_or_id!r} in {str(self.path)!r}; sweeps: {names}")
        return int(row[0])

    # -- runs ------------------------------------------------------------------------------------------------
    def statuses(self) -> dict[tuple[str, int], str]:
        """``(scenario_hash, seed) -> status`` of every stored run."""
        return {(h, s): st for h, s, st in self.conn.execute("SELECT scenario_hash, seed, status FROM runs")}

    def record(self, scenario_hash: str, seed: int, scenario: dict[str, Any], outcome: dict[str, Any]) -> None:
        """Write one finished run (what :func:`~amronet.sweeps.worker.execute_job` returned) in one transaction.

        A run already stored under the same key is replaced (a retried failure), with its time series.
        """
        summary = outcome.get("summary")
        ts = outcome.get("timeseries") or {}
        metrics = [summary.get(k) if summary else None for k in METRIC_COLUMNS]
        row = (scenario_hash, int(seed), canonical_json(scenario), outcome["status"], outcome.get("error"),
               json.dumps(summary, allow_nan=True) if summary is not None else None, *metrics,
               json.dumps(list(ts)) if summary is not None else None, outcome["amronet_version"],
               outcome.get("host"), outcome.get("wall_time_s"), _now())
        with self._transaction() as c:
            for name in ts:
                if name not in self._ts_columns:
                    if not _IDENT.match(name):
                        raise StoreError(f"timeseries: column name {name!r} cannot be stored")
                    c.execute(f'ALTER TABLE timeseries ADD COLUMN "{name}" REAL')
                    self._ts_columns.append(name)
            c.execute("DELETE FROM timeseries WHERE scenario_hash = ? AND seed = ?", (scenario_hash, int(seed)))
            c.execute(f"INSERT OR REPLACE INTO runs VALUES ({', '.join('?' * len(row))})", row)
            if ts:
                names = list(ts)
                n = len(ts[names[0]])
                cols = ", ".join(f'"{x}"' for x in names)
                c.executemany(
                    f"INSERT INTO timeseries (scenario_hash, seed, k, {cols}) VALUES (?, ?, ?{', ?' * len(names)})",
                    [(scenario_hash, int(seed), k, *(ts[x][k] for x in names)) for k in range(n)])

    def load(self, scenario_hash: str, seed: int, timeseries: bool = True) -> dict[str, Any] | None:
        """A stored run as ``{"status", "error", "summary", "timeseries"}``; ``None`` when it is not stored.

        The summary is the one :class:`~amronet.sim.results.RunResult` made, with ``wall_time_s``,
        ``amronet_version`` and ``scenario`` (the resolved scenario) last.
        """
        row = self.conn.execute(
            "SELECT status, error, summary, timeseries_columns, wall_time_s, amronet_version, scenario FROM runs "
            "WHERE scenario_hash = ? AND seed = ?", (scenario_hash, int(seed))).fetchone()
        if row is None:
            return None
        status, error, summary_text, ts_cols, wall, version, scenario = row
        out: dict[str, Any] = {"status": status, "error": error, "summary": None, "timeseries": None}
        if summary_text is not None:
            summary = json.loads(summary_text)
            summary.update(zip(SUMMARY_EXTRAS, (wall, version, json.loads(scenario)), strict=True))
            out["summary"] = summary
        if timeseries and ts_cols is not None:
            names = json.loads(ts_cols)
            cols = ", ".join(f'"{x}"' for x in names)
            rows = self.conn.execute(f"SELECT {cols} FROM timeseries WHERE scenario_hash = ? AND seed = ? ORDER BY k",
                                     (scenario_hash, int(seed))).fetchall() if names else []
            out["timeseries"] = {x: [r[j] for r in rows] for j, x in enumerate(names)}
        return out

    def runs(self, sweep_id: int | None = None) -> list[dict[str, Any]]:
        """Stored runs as dicts (every column of ``runs``; with a sweep also ``point`` and ``labels``).

        ``scenario``, ``summary`` and ``labels`` are decoded from JSON. Ordered by sweep point and seed, or by key.
        """
        if sweep_id is None:
            cur = self.conn.execute("SELECT * FROM runs ORDER BY scenario_hash, seed")
        else:
            cur = self.conn.execute(
                "SELECT r.*, l.point AS point, l.labels AS labels FROM sweep_runs l JOIN runs r "
                "ON r.scenario_hash = l.scenario_hash AND r.seed = l.seed WHERE l.sweep_id = ? "
                "ORDER BY l.point, l.seed", (sweep_id,))
        names = [d[0] for d in cur.description]
        out = []
        for values in cur:
            row = dict(zip(names, values, strict=True))
            for key in ("scenario", "summary", "labels", "timeseries_columns"):
                if row.get(key) is not None:
                    row[key] = json.loads(row[key])
            out.append(row)
        return out

    def links(self, sweep_id: int | None = None) -> list[dict[str, Any]]:
        """Rows of ``sweep_runs`` with the sweep's name (all sweeps, or one)."""
        sql = ("SELECT l.sweep_id, s.name AS sweep, l.scenario_hash, l.seed, l.point, l.labels FROM sweep_runs l "
               "JOIN sweeps s ON s.id = l.sweep_id")
        args: tuple[Any, ...] = ()
        if sweep_id is not None:
            sql, args = sql + " WHERE l.sweep_id = ?", (sweep_id,)
        cur = self.conn.execute(sql + " ORDER BY l.sweep_id, l.point, l.seed", args)
        names = [d[0] for d in cur.description]
        return [{**dict(zip(names, v, strict=True)), "labels": json.loads(v[-1])} for v in cur]

    def timeseries_rows(self, sweep_id: int | None = None) -> tuple[list[str], list[tuple[Any, ...]]]:
        """Column names and rows of ``timeseries`` (all runs, or those of one sweep)."""
        if sweep_id is None:
            cur = self.conn.execute("SELECT * FROM timeseries ORDER BY scenario_hash, seed, k")
        else:
            cur = self.conn.execute(
                "SELECT t.* FROM timeseries t JOIN sweep_runs l ON l.scenario_hash = t.scenario_hash "
                "AND l.seed = t.seed WHERE l.sweep_id = ? ORDER BY l.point, t.seed, t.k", (sweep_id,))
        return [d[0] for d in cur.description], cur.fetchall()
