"""Optima in the result store: a solved optimum problem kept like a finished run, under a hash of the problem.

The store does not know what an optimum is: it keeps, under a ``key`` (the caller's hash of the problem, see
:mod:`amronet.optimum.stored`), the problem as canonical JSON and the answer as JSON, written in one transaction
(``synchronous = FULL``, as every finished run), so a figure or a command stopped half way keeps every optimum it
finished and solves only the others when run again.
"""

from __future__ import annotations

import json
from typing import Any

from amronet.sweeps.identity import canonical_json
from amronet.sweeps.store_errors import stored_json
from amronet.sweeps.store_schema import OPTIMA_TABLE, StoreFile, utc_now
from amronet.version import __version__

__all__ = ["StoreOptima"]


class StoreOptima(StoreFile):
    """Reading and writing the ``optima`` table (:mod:`~amronet.sweeps.store_schema`)."""

    def stored_optimum(self, key: str) -> dict[str, Any] | None:
        """The answer stored under ``key``, ``None`` when there is none.

        Raises:
            StoreError: The stored answer is damaged.
        """
        if not self._optima_table:  # a store from before optima, opened for reading
            return None
        row = self.conn.execute("SELECT result FROM optima WHERE key = ?", (key,)).fetchone()
        return None if row is None else stored_json(row[0], self.path, self.option, "optima.result")

    def record_optimum(self, key: str, instance: dict[str, Any], result: dict[str, Any],
                       wall_time_s: float | None = None) -> None:
        """Keep a solved problem's answer under ``key``, in one transaction (an answer under the key is replaced).

        Args:
            key: The problem's hash.
            instance: The problem, as plain data (stored as canonical JSON, for the record).
            result: The answer, as plain data.
            wall_time_s: Seconds it took.
        """
        with self._transaction() as c:
            if not self._optima_table:
                c.execute(OPTIMA_TABLE)
                self._optima_table = True
            c.execute("INSERT OR REPLACE INTO optima VALUES (?, ?, ?, ?, ?, ?)",
                      (key, canonical_json(instance), json.dumps(result, allow_nan=True), __version__, wall_time_s,
                       utc_now()))
