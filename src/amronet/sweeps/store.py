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
* ``claims`` — the runs some process is computing right now: key, the ``owner`` (a random token per sweep
  invocation), its ``host`` and ``pid``, ``claimed_at`` and a ``heartbeat`` (Unix time, refreshed every
  :data:`CLAIM_HEARTBEAT_S` s). A claim is taken with ``BEGIN IMMEDIATE`` (:meth:`ResultStore.claim`) and
  dropped in the transaction that records its run, or when its owner stops. So two sweeps on one store never
  compute a run twice: the second leaves a run claimed by a live owner to it, and takes over a *stale* claim —
  its owner's process is gone (same host) or its heartbeat is older than :data:`CLAIM_LEASE_S` s (any host).
  Stores written before claims existed gain the (empty) table when a sweep opens them.

Every finished run is written in one transaction with ``synchronous = FULL``: after a crash (``SIGKILL``, power
loss) the file holds every run whose transaction committed and nothing of the others, so running the sweep
again completes exactly the missing ones. Only the parents of the workers write (one per sweep process).
Creating the store tolerates other processes creating it at the same instant: the schema is created with
``IF NOT EXISTS`` in one ``BEGIN IMMEDIATE`` transaction, behind SQLite's busy timeout.

A path that exists but is not an amronet store (another SQLite database, a text file) is refused before it is
opened, so it is left byte for byte as it was.
"""

from __future__ import annotations

import json
import os
import re
import socket
import sqlite3
import threading
import time
import uuid
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from itertools import repeat
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError
from amronet.sweeps.identity import canonical_json
from amronet.sweeps.worker import SUMMARY_EXTRAS, pid_alive

__all__ = ["APPLICATION_ID", "CLAIM_HEARTBEAT_S", "CLAIM_LEASE_S", "METRIC_COLUMNS", "ClaimOwner", "Claims",
           "ResultStore", "StoreError"]

APPLICATION_ID = 0x414D524E
"""SQLite ``application_id`` of an amronet result store ("AMRN")."""
SCHEMA_VERSION = 1
METRIC_COLUMNS = ("nodes_total", "routers_deployed", "coverage", "connected_coverage", "stop_reason", "sim_time_s")
"""Summary fields copied into columns of ``runs``."""
TIMESERIES_COLUMNS = ("t", "coverage", "connected_coverage", "routers_deployed", "components", "agents_connected")
WALL_TIME_COLUMNS = ("wall_time_s", "finished_at", "created")
"""Columns that differ between two otherwise identical sweeps."""
CLAIM_LEASE_S = 60.0
"""A claim whose heartbeat is older than this is stale: another process may take its run over."""
CLAIM_HEARTBEAT_S = 5.0
"""How often a sweep refreshes the heartbeat of its claims."""

_MAGIC = b"SQLite format 3\x00"
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")

_CLAIMS = """
CREATE TABLE IF NOT EXISTS claims (
    scenario_hash TEXT NOT NULL,
    seed INTEGER NOT NULL,
    owner TEXT NOT NULL,
    host TEXT NOT NULL,
    pid INTEGER NOT NULL,
    claimed_at TEXT NOT NULL,
    heartbeat REAL NOT NULL,
    PRIMARY KEY (scenario_hash, seed)
) WITHOUT ROWID;
"""

_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS sweeps (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL,
    spec TEXT NOT NULL,
    spec_hash TEXT NOT NULL UNIQUE,
    created TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS runs (
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
CREATE TABLE IF NOT EXISTS sweep_runs (
    sweep_id INTEGER NOT NULL REFERENCES sweeps (id),
    scenario_hash TEXT NOT NULL,
    seed INTEGER NOT NULL,
    point INTEGER NOT NULL,
    labels TEXT NOT NULL,
    PRIMARY KEY (sweep_id, scenario_hash, seed)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS timeseries (
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
{_CLAIMS}
PRAGMA application_id = {APPLICATION_ID};
PRAGMA user_version = {SCHEMA_VERSION};
"""


class StoreError(AmronetError):
    """The result store cannot be used (not a store, unreadable, a newer schema)."""


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


RunKey = tuple[str, int]
"""``(scenario_hash, seed)``."""
RunVersion = tuple[str, str, float | None]
"""A stored run's ``(status, finished_at, wall_time_s)``: tells one recording of a run from the next."""


@dataclass(frozen=True)
class ClaimOwner:
    """Who holds claims: one sweep invocation (a random token), on a host, in a process."""

    token: str
    host: str
    pid: int

    @classmethod
    def new(cls) -> ClaimOwner:
        """A fresh owner for this process."""
        return cls(uuid.uuid4().hex, socket.gethostname(), os.getpid())


@dataclass
class Claims:
    """What :meth:`ResultStore.claim` found for the runs asked about.

    Attributes:
        claimed: Runs claimed now by the caller: compute them.
        finished: Runs recorded by another process since the caller looked (``status`` by key): do not compute.
        held: Runs claimed by another live owner (``"pid P on HOST"`` by key): wait for them.
    """

    claimed: list[RunKey] = field(default_factory=list)
    finished: dict[RunKey, str] = field(default_factory=dict)
    held: dict[RunKey, str] = field(default_factory=dict)


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
                # created in rollback-journal mode, so the header with the application id reaches the main file;
                # IF NOT EXISTS: another process may have created it since we looked (two sweeps started at once)
                self.conn.executescript("BEGIN IMMEDIATE;" + _SCHEMA + "COMMIT;")
            else:
                version = self.conn.execute("PRAGMA user_version").fetchone()[0]
                if version > SCHEMA_VERSION:
                    raise StoreError(f"{option}: {str(self.path)!r} was written by a newer amronet "
                                     f"(schema {version}); upgrade amronet")
            self._use_wal()
            self.conn.execute("PRAGMA synchronous = FULL")
            self._ts_columns = [r[1] for r in self.conn.execute("PRAGMA table_info(timeseries)")]
            self._claims_table = self._has_claims()
            if not must_exist and not self._claims_table:
                self.conn.execute(_CLAIMS)  # a store from before claims: add the table (nothing else changes)
                self._claims_table = True
        except sqlite3.DatabaseError as exc:
            self.conn.close()
            raise StoreError(f"{option}: {str(self.path)!r} is damaged or not a result store: {exc}") from None

    # -- plumbing --------------------------------------------------------------------------------------------
    def _use_wal(self, timeout: float = 60.0) -> None:
        """Switch the file to WAL mode (once; a no-op after).

        SQLite may refuse the switch with "database is locked" without waiting while other processes open the same
        new store, so this retries for ``timeout`` seconds.
        """
        deadline = time.monotonic() + timeout
        while True:
            try:
                if self.conn.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
                    self.conn.execute("PRAGMA journal_mode = WAL")
                return
            except sqlite3.OperationalError as exc:
                if ("locked" not in str(exc) and "busy" not in str(exc)) or time.monotonic() > deadline:
                    raise
                time.sleep(0.01)

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

    # -- claims ----------------------------------------------------------------------------------------------
    def _has_claims(self) -> bool:
        return self.conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'claims'").fetchone() \
            is not None

    def versions(self) -> dict[RunKey, RunVersion]:
        """``(scenario_hash, seed) -> (status, finished_at, wall_time_s)`` of every stored run."""
        return {(h, s): (st, f, w) for h, s, st, f, w in self.conn.execute(
            "SELECT scenario_hash, seed, status, finished_at, wall_time_s FROM runs")}

    def claim(self, keys: Iterable[RunKey], owner: ClaimOwner, seen: dict[RunKey, RunVersion | None],
              lease: float = CLAIM_LEASE_S) -> Claims:
        """Claim the runs ``keys`` for ``owner``, in one ``BEGIN IMMEDIATE`` transaction.

        A run is claimed when it is still as the caller saw it (``seen``: missing, or the failed recording it
        means to retry) and nobody else holds a live claim on it (none, the caller's own, or a stale one: its
        owner's process is gone on this host, or its heartbeat is older than ``lease`` seconds).

        Returns:
            :class:`Claims`: claimed now, finished by another process meanwhile, held by another live owner.
        """
        out = Claims()
        now = time.time()
        alive: dict[tuple[str, int], bool] = {}

        def stale(host: str, pid: int, heartbeat: float) -> bool:
            if now - heartbeat > lease:
                return True
            if host != owner.host:
                return False
            if (host, pid) not in alive:
                alive[(host, pid)] = pid_alive(pid)
            return not alive[(host, pid)]

        with self._transaction() as c:
            if not self._claims_table:
                c.execute(_CLAIMS)
                self._claims_table = True
            versions = self.versions()
            holders = {(h, s): (o, host, pid, hb) for h, s, o, host, pid, hb in c.execute(
                "SELECT scenario_hash, seed, owner, host, pid, heartbeat FROM claims")}
            rows = []
            for key in keys:
                key = (key[0], int(key[1]))
                version = versions.get(key)
                if version is not None and (version[0] == "done" or version != seen.get(key)):
                    out.finished[key] = version[0]
                    continue
                holder = holders.get(key)
                if holder is not None and holder[0] != owner.token and not stale(*holder[1:]):
                    out.held[key] = f"pid {holder[2]} on {holder[1]}"
                    continue
                out.claimed.append(key)
                rows.append((*key, owner.token, owner.host, owner.pid, _now(), now))
            c.executemany("INSERT OR REPLACE INTO claims VALUES (?, ?, ?, ?, ?, ?, ?)", rows)
        return out

    def release(self, owner: ClaimOwner) -> None:
        """Drop every claim of ``owner`` (its runs not recorded yet become free for others)."""
        if self._claims_table:
            with self._transaction() as c:
                c.execute("DELETE FROM claims WHERE owner = ?", (owner.token,))

    @contextmanager
    def heartbeat(self, owner: ClaimOwner, interval: float = CLAIM_HEARTBEAT_S) -> Iterator[None]:
        """Refresh the heartbeat of ``owner``'s claims every ``interval`` seconds while the block runs.

        A thread with its own connection does it, so that other processes see the claims live however long a run
        takes.
        """
        stop = threading.Event()

        def beat() -> None:
            conn = sqlite3.connect(self.path, isolation_level=None, timeout=interval)
            try:
                while not stop.wait(interval):
                    try:
                        conn.execute("UPDATE claims SET heartbeat = ? WHERE owner = ?", (time.time(), owner.token))
                    except sqlite3.Error:
                        continue  # busy for a whole interval: the next beat
            finally:
                conn.close()

        thread = threading.Thread(target=beat, name="amronet-claims-heartbeat", daemon=True)
        thread.start()
        try:
            yield
        finally:
            stop.set()
            thread.join(timeout=2 * interval)

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
            if self._claims_table:
                c.execute("DELETE FROM claims WHERE scenario_hash = ? AND seed = ?", (scenario_hash, int(seed)))
            if ts:
                names = list(ts)
                n = len(ts[names[0]])
                cols = ", ".join(f'"{x}"' for x in names)
                c.executemany(
                    f"INSERT INTO timeseries (scenario_hash, seed, k, {cols}) VALUES (?, ?, ?{', ?' * len(names)})",
                    zip(repeat(scenario_hash, n), repeat(int(seed), n), range(n), *(ts[x] for x in names), strict=True))

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
