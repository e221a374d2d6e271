"""The result store's file: its tables, how a path is recognised as a store, and how it is opened.

Tables:

* ``runs`` — one row per (``scenario_hash``, ``seed``): the resolved scenario (canonical JSON), ``status``
  (``done`` or ``failed``), the one-line ``error`` of a failed run, the ``summary`` (JSON, without the fields
  kept in columns), the main metrics as columns (:data:`METRIC_COLUMNS`), ``amronet_version``, ``host``, and the
  wall-time columns ``wall_time_s`` and ``finished_at``.
* ``timeseries`` — one row per recorded step of a done run (``k`` = 0, 1, ...): ``t``, ``coverage``,
  ``connected_coverage``, ``routers_deployed``, ``components``, ``agents_connected`` (and any other column a run
  records, added when first written).
* ``sweeps`` — ``id``, ``name``, ``spec`` (canonical JSON), ``spec_hash`` (unique), ``created``.
* ``sweep_runs`` — which runs belong to which sweep, at which ``point``, with the point's ``labels`` (JSON: the
  swept keys' values, or a figure's labels). A run belongs to every sweep that contains it.
* ``claims`` — the runs some process is computing right now (:mod:`amronet.sweeps.store_claims`). Stores written
  before claims existed gain the (empty) table when a sweep opens them.
* ``optima`` — one row per solved optimum problem (:mod:`amronet.sweeps.store_optima`): its ``key`` (a hash of the
  problem, as a run's scenario hash), the problem (``instance``, canonical JSON), the answer (``result``, what
  ``optimum.json`` holds), ``amronet_version``, ``wall_time_s`` and ``finished_at``. Stores written before optima
  existed gain the (empty) table when they are opened for writing.

Creating the store tolerates other processes creating it at the same instant: the schema is created with
``IF NOT EXISTS`` in one ``BEGIN IMMEDIATE`` transaction, behind SQLite's busy timeout. A path that exists but is
not an amronet store (another SQLite database, a text file) is refused before it is opened, so it is left byte
for byte as it was.
"""

from __future__ import annotations

import contextlib
import sqlite3
import time
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Self

from amronet.sweeps.store_errors import GuardedConnection, StoreError, store_error

__all__ = ["APPLICATION_ID", "METRIC_COLUMNS", "OPTIMA_TABLE", "SCHEMA_VERSION", "RunKey", "RunVersion", "StoreError",
           "StoreFile", "check_store_path"]

APPLICATION_ID = 0x414D524E
"""SQLite ``application_id`` of an amronet result store ("AMRN")."""
SCHEMA_VERSION = 1
METRIC_COLUMNS = ("nodes_total", "routers_deployed", "coverage", "connected_coverage", "stop_reason", "sim_time_s")
"""Summary fields copied into columns of ``runs``."""

_MAGIC = b"SQLite format 3\x00"

CLAIMS_TABLE = """
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

OPTIMA_TABLE = """
CREATE TABLE IF NOT EXISTS optima (
    key TEXT NOT NULL PRIMARY KEY,
    instance TEXT NOT NULL,
    result TEXT NOT NULL,
    amronet_version TEXT NOT NULL,
    wall_time_s REAL,
    finished_at TEXT NOT NULL
) WITHOUT ROWID;
"""

SCHEMA = f"""
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
{CLAIMS_TABLE}
{OPTIMA_TABLE}
PRAGMA application_id = {APPLICATION_ID};
PRAGMA user_version = {SCHEMA_VERSION};
"""

RunKey = tuple[str, int]
"""``(scenario_hash, seed)``."""
RunVersion = tuple[str, str, float | None]
"""A stored run's ``(status, finished_at, wall_time_s)``: tells one recording of a run from the next."""


def utc_now() -> str:
    """The time now, UTC, to the second (ISO 8601): what ``created``, ``finished_at`` and ``claimed_at`` hold."""
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


class StoreFile:
    """An open store file: checked, created with the schema when new, in WAL mode with ``synchronous = FULL``.

    Args:
        path: The SQLite file; created (with its folder) unless ``must_exist``.
        must_exist: Refuse to create a new store (for reading).
        option: How errors name the path (``--store``, or ``STORE`` for ``amronet results`` and ``plot``).

    Raises:
        StoreError: See :func:`check_store_path`; or the file is damaged or from a newer amronet.
    """

    def __init__(self, path: str | Path, must_exist: bool = False, option: str = "--store") -> None:
        self.path = Path(path)
        self.option = option
        exists = check_store_path(self.path, must_exist=must_exist, option=option)
        try:
            if not exists:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            conn = sqlite3.connect(self.path, isolation_level=None, timeout=60.0)
        except (OSError, sqlite3.Error) as exc:
            raise StoreError(f"{option}: cannot open {str(self.path)!r}: {exc}") from None
        self.conn = GuardedConnection(conn, self.path, option)
        """The connection: its SQLite errors are :class:`StoreError` (:mod:`amronet.sweeps.store_errors`)."""
        try:
            self.conn.execute("PRAGMA busy_timeout = 60000")
            if not exists:
                # created in rollback-journal mode, so the header with the application id reaches the main file;
                # IF NOT EXISTS: another process may have created it since we looked (two sweeps started at once)
                self.conn.executescript("BEGIN IMMEDIATE;" + SCHEMA + "COMMIT;")
            else:
                version = self.conn.execute("PRAGMA user_version").fetchone()[0]
                if version > SCHEMA_VERSION:
                    raise StoreError(f"{option}: {str(self.path)!r} was written by a newer amronet "
                                     f"(schema {version}); upgrade amronet")
                if not must_exist:
                    self._check_pages()
            self._use_wal()
            self.conn.execute("PRAGMA synchronous = FULL")
            self._ts_columns = [r[1] for r in self.conn.execute("PRAGMA table_info(timeseries)")]
            self._claims_table = self._has_claims()
            if not must_exist and not self._claims_table:
                self.conn.execute(CLAIMS_TABLE)  # a store from before claims: add the table (nothing else changes)
                self._claims_table = True
            self._optima_table = self._has_table("optima")
            if not must_exist and not self._optima_table:
                self.conn.execute(OPTIMA_TABLE)  # a store from before optima: likewise
                self._optima_table = True
        except StoreError:
            conn.close()
            raise

    def _check_pages(self) -> None:
        """Before writing to an existing store, check its pages (SQLite's ``quick_check``: about 1.5 s per GB).

        Some damage reads without an error (a page of a long text zeroed, a value that breaks its table's
        ``CHECK``): a sweep would take such runs as missing and write over them. A damaged store is refused and
        left as it was.
        """
        problems = [row[0] for row in self.conn.execute("PRAGMA quick_check(4)")]
        if problems != ["ok"]:
            first = next((p for p in problems if not p.startswith("***")), problems[0])
            raise store_error(sqlite3.DatabaseError(f"database disk image is malformed: {first}"), self.path,
                              self.option)

    def _use_wal(self, timeout: float = 60.0) -> None:
        """Switch the file to WAL mode (once; a no-op after).

        SQLite may refuse the switch with "database is locked" without waiting while other processes open the same
        new store, so this retries for ``timeout`` seconds.
        """
        deadline = time.monotonic() + timeout
        raw = self.conn.raw
        while True:
            try:
                if raw.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
                    raw.execute("PRAGMA journal_mode = WAL")
                return
            except sqlite3.DatabaseError as exc:
                if ("locked" not in str(exc) and "busy" not in str(exc)) or time.monotonic() > deadline:
                    raise store_error(exc, self.path, self.option) from None
                time.sleep(0.01)

    def _has_claims(self) -> bool:
        return self._has_table("claims")

    def _has_table(self, name: str) -> bool:
        return self.conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", (name,)).fetchone() \
            is not None

    def close(self) -> None:
        """Close the store (the WAL is checkpointed into the main file)."""
        self.conn.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @contextmanager
    def _transaction(self) -> Iterator[GuardedConnection]:
        self.conn.execute("BEGIN IMMEDIATE")
        try:
            yield self.conn
        except BaseException:
            if self.conn.in_transaction:  # SQLite may have rolled back itself (a damaged page, a full disk)
                with contextlib.suppress(StoreError):
                    self.conn.execute("ROLLBACK")
            raise
        self.conn.execute("COMMIT")
