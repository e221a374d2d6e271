"""The result store: one SQLite file (WAL mode) that never loses a finished run.

:class:`ResultStore` is the store; its parts live beside it: the tables and opening the file
(:mod:`~amronet.sweeps.store_schema`), the claims of runs being computed (:mod:`~amronet.sweeps.store_claims`),
the queries (:mod:`~amronet.sweeps.store_reading`), the solved optimum problems
(:mod:`~amronet.sweeps.store_optima`). This module writes: a sweep and its runs' links, and every finished run.

Every finished run is written in one transaction with ``synchronous = FULL``: after a crash (``SIGKILL``, power
loss) the file holds every run whose transaction committed and nothing of the others, so running the sweep
again completes exactly the missing ones. Only the parents of the workers write (one per sweep process).
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Iterable
from itertools import repeat
from typing import Any

from amronet.sweeps.identity import canonical_json
from amronet.sweeps.store_claims import CLAIM_HEARTBEAT_S, CLAIM_LEASE_S, ClaimOwner, Claims, StoreClaims
from amronet.sweeps.store_optima import StoreOptima
from amronet.sweeps.store_reading import StoreReading
from amronet.sweeps.store_schema import (
    APPLICATION_ID,
    METRIC_COLUMNS,
    RunKey,
    RunVersion,
    StoreError,
    check_store_path,
    utc_now,
)

__all__ = ["APPLICATION_ID", "CLAIM_HEARTBEAT_S", "CLAIM_LEASE_S", "METRIC_COLUMNS", "ClaimOwner", "Claims",
           "ResultStore", "RunKey", "RunVersion", "StoreError", "check_store_path"]

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class ResultStore(StoreClaims, StoreReading, StoreOptima):
    """An open result store (see the module docstring).

    Args:
        path: The SQLite file; created (with its folder) unless ``must_exist``.
        must_exist: Refuse to create a new store (for reading).
        option: How errors name the path (``--store``, or ``STORE`` for ``amronet results`` and ``plot``).

    Raises:
        StoreError: See :func:`check_store_path`; or the file is damaged or from a newer amronet.
    """

    def add_sweep(self, name: str, spec: dict[str, Any], links: Iterable[tuple[str, int, int, dict[str, Any]]]) -> int:
        """Register a sweep (or find the identical one) and link its runs, in one transaction.

        Args:
            name: The sweep's name.
            spec: Its specification (stored as canonical JSON; identical specs are one sweep).
            links: ``(scenario_hash, seed, point, labels)`` of every run of the sweep.

        Returns:
            The sweep's id.
        """
        text = canonical_json(spec)
        digest = hashlib.sha256(text.encode()).hexdigest()
        with self._transaction() as c:
            c.execute("INSERT OR IGNORE INTO sweeps (name, spec, spec_hash, created) VALUES (?, ?, ?, ?)",
                      (name, text, digest, utc_now()))
            sweep_id = c.execute("SELECT id FROM sweeps WHERE spec_hash = ?", (digest,)).fetchone()[0]
            c.executemany("INSERT OR IGNORE INTO sweep_runs (sweep_id, scenario_hash, seed, point, labels) "
                          "VALUES (?, ?, ?, ?, ?)",
                          [(sweep_id, h, s, p, canonical_json(lab)) for h, s, p, lab in links])
        return int(sweep_id)

    def record(self, scenario_hash: str, seed: int, scenario: dict[str, Any], outcome: dict[str, Any]) -> None:
        """Write one finished run (what :func:`~amronet.sweeps.worker.execute_job` returned) in one transaction.

        A run already stored under the same key is replaced (a retried failure), with its time series; its claim
        (:mod:`~amronet.sweeps.store_claims`) is dropped in the same transaction.
        """
        summary = outcome.get("summary")
        ts = outcome.get("timeseries") or {}
        metrics = [summary.get(k) if summary else None for k in METRIC_COLUMNS]
        row = (scenario_hash, int(seed), canonical_json(scenario), outcome["status"], outcome.get("error"),
               json.dumps(summary, allow_nan=True) if summary is not None else None, *metrics,
               json.dumps(list(ts)) if summary is not None else None, outcome["amronet_version"],
               outcome.get("host"), outcome.get("wall_time_s"), utc_now())
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
