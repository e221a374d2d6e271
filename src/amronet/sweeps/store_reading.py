"""Reading the result store: its sweeps, its runs (one, or all of a sweep), their links and time series."""

from __future__ import annotations

from typing import Any

from amronet.sweeps.store_errors import stored_json
from amronet.sweeps.store_schema import StoreError, StoreFile
from amronet.sweeps.worker import SUMMARY_EXTRAS

__all__ = ["StoreReading"]


class StoreReading(StoreFile):
    """The queries of a result store (tables: :mod:`amronet.sweeps.store_schema`)."""

    def _json(self, text: str, what: str) -> Any:
        """Stored JSON text decoded; damaged text is a :class:`StoreError` naming the column ``what``."""
        return stored_json(text, self.path, self.option, what)

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

    def statuses(self) -> dict[tuple[str, int], str]:
        """``(scenario_hash, seed) -> status`` of every stored run."""
        return {(h, s): st for h, s, st in self.conn.execute("SELECT scenario_hash, seed, status FROM runs")}

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
            summary = self._json(summary_text, "runs.summary")
            summary.update(zip(SUMMARY_EXTRAS, (wall, version, self._json(scenario, "runs.scenario")), strict=True))
            out["summary"] = summary
        if timeseries and ts_cols is not None:
            names = self._json(ts_cols, "runs.timeseries_columns")
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
                    row[key] = self._json(row[key], key)
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
        return [{**dict(zip(names, v, strict=True)), "labels": self._json(v[-1], "sweep_runs.labels")} for v in cur]

    def timeseries_rows(self, sweep_id: int | None = None) -> tuple[list[str], list[tuple[Any, ...]]]:
        """Column names and rows of ``timeseries`` (all runs, or those of one sweep)."""
        if sweep_id is None:
            cur = self.conn.execute("SELECT * FROM timeseries ORDER BY scenario_hash, seed, k")
        else:
            cur = self.conn.execute(
                "SELECT t.* FROM timeseries t JOIN sweep_runs l ON l.scenario_hash = t.scenario_hash "
                "AND l.seed = t.seed WHERE l.sweep_id = ? ORDER BY l.point, t.seed, t.k", (sweep_id,))
        return [d[0] for d in cur.description], cur.fetchall()
