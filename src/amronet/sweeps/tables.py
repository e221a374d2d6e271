"""Tidy tables from the result store: one row per run, per sweep membership, per recorded step.

Column names of a run are the dotted keys of ``--set`` (``radio.r_c``, ``algorithm.params.triangular``,
``base_stations.0.x``) for the resolved scenario, the summary fields (``nodes_total``, ``coverage``,
``states.explore``...), and, for the runs of one sweep, its labels first (the swept keys' values, or a
figure's labels such as ``r_c``, ``agents``). :func:`export_tables` writes them as CSV or Parquet.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from amronet.errors import AmronetError
from amronet.outputs.files import write_files_atomically
from amronet.sweeps.stats import mean_ci
from amronet.sweeps.store import ResultStore

__all__ = ["export_tables", "flatten", "point_summary", "run_rows"]

_RUN_COLUMNS = ("scenario_hash", "seed", "status", "error")
_TAIL_COLUMNS = ("wall_time_s", "amronet_version", "host", "finished_at")


def flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    """Nested dicts and lists as one flat dict with dotted keys (list items by index: ``base_stations.0.x``)."""
    out: dict[str, Any] = {}
    if isinstance(data, dict) and data:
        for key, value in data.items():
            out.update(flatten(value, f"{prefix}.{key}" if prefix else str(key)))
    elif isinstance(data, list) and data:
        for k, value in enumerate(data):
            out.update(flatten(value, f"{prefix}.{k}" if prefix else str(k)))
    else:
        out[prefix] = data
    return out


def run_rows(store: ResultStore, sweep_id: int | None = None) -> list[dict[str, Any]]:
    """One flat dict per run (of one sweep, with its labels and ``point``, or of the whole store)."""
    rows = []
    for run in store.runs(sweep_id):
        row = {k: run[k] for k in _RUN_COLUMNS}
        if sweep_id is not None:
            row["point"] = run["point"]
            for key, value in flatten(run["labels"]).items():
                row.setdefault(key, value)
        for key, value in flatten(run["scenario"]).items():
            row.setdefault(key, value)
        for key, value in flatten(run["summary"] or {}).items():
            row.setdefault(key, value)
        for key in _TAIL_COLUMNS:
            row.setdefault(key, run[key])
        rows.append(row)
    return rows


def point_summary(rows: list[dict[str, Any]], keys: list[str]) -> list[dict[str, Any]]:
    """Aggregate runs per sweep point.

    Returns:
        Per point: its index, the swept keys' values, its ``scenario_hash``, runs, done, failed, mean ± 95 % CI
        of ``nodes_total``, means of ``coverage`` and ``connected_coverage``, and the most common stop reason.
    """
    groups: dict[Any, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(row.get("point"), []).append(row)
    out = []
    for point, sel in groups.items():
        done = [r for r in sel if r["status"] == "done"]
        mean, half = mean_ci(np.array([r["nodes_total"] for r in done], dtype=float))
        reasons = Counter(r.get("stop_reason") for r in done)
        entry = {"point": point, **{k: sel[0].get(k) for k in keys}, "scenario_hash": sel[0]["scenario_hash"],
                 "runs": len(sel), "done": len(done),
                 "failed": len(sel) - len(done), "nodes_total_mean": mean, "nodes_total_ci95": half,
                 "coverage_mean": float(np.mean([r["coverage"] for r in done])) if done else math.nan,
                 "connected_coverage_mean": (float(np.mean([r["connected_coverage"] for r in done]))
                                             if done else math.nan),
                 "stop_reason": reasons.most_common(1)[0][0] if reasons else ""}
        out.append(entry)
    return out


def _columns(rows: list[dict[str, Any]]) -> list[str]:
    return list(dict.fromkeys(k for row in rows for k in row))


def _cell(value: Any) -> Any:
    if isinstance(value, dict | list):
        return json.dumps(value)
    return value


def _text(value: Any) -> str:
    if isinstance(value, str):
        return value
    return json.dumps(value) if isinstance(value, dict | list) else str(value)


def _csv_bytes(rows: list[dict[str, Any]], columns: list[str]) -> bytes:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow(["" if row.get(c) is None else _cell(row.get(c)) for c in columns])
    return buf.getvalue().encode()


def _parquet_bytes(rows: list[dict[str, Any]], columns: list[str]) -> bytes:
    import pyarrow as pa
    import pyarrow.parquet as pq

    arrays = {}
    for c in columns:
        values = [row.get(c) for row in rows]
        present = [v for v in values if v is not None]
        if present and all(isinstance(v, bool) for v in present):
            arrays[c] = pa.array(values, type=pa.bool_())
        elif present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
            arrays[c] = pa.array(values, type=pa.int64())
        elif present and all(isinstance(v, int | float) and not isinstance(v, bool) for v in present):
            arrays[c] = pa.array([None if v is None else float(v) for v in values], type=pa.float64())
        else:
            arrays[c] = pa.array([None if v is None else _text(v) for v in values], type=pa.string())
    buf = io.BytesIO()
    pq.write_table(pa.table(arrays), buf)
    return buf.getvalue()


def tables(store: ResultStore, sweep_id: int | None = None) -> dict[str, tuple[list[str], list[dict[str, Any]]]]:
    """The tidy tables: ``runs``, ``sweeps``, ``sweep_runs`` and ``timeseries`` as (columns, rows)."""
    runs = run_rows(store, sweep_id)
    sweeps = store.sweeps()
    if sweep_id is not None:
        sweeps = [s for s in sweeps if s["id"] == sweep_id]
    links = [{k: v for k, v in link.items() if k != "labels"} | flatten(link["labels"])
             for link in store.links(sweep_id)]
    ts_columns, ts_values = store.timeseries_rows(sweep_id)
    ts_rows = [dict(zip(ts_columns, v, strict=True)) for v in ts_values]
    ts_keep = [c for c in ts_columns if any(r[c] is not None for r in ts_rows)] or ts_columns
    return {"runs": (_columns(runs) or list(_RUN_COLUMNS), runs),
            "sweeps": (["id", "name", "created", "runs", "done", "failed", "missing"], sweeps),
            "sweep_runs": (_columns(links) or ["sweep_id", "sweep", "scenario_hash", "seed", "point"], links),
            "timeseries": (ts_keep, ts_rows)}


def export_tables(store: ResultStore, fmt: str, out_dir: str | Path, sweep_id: int | None = None) -> dict[str, int]:
    """Write ``runs``, ``sweeps``, ``sweep_runs`` and ``timeseries`` as ``.csv`` or ``.parquet`` into ``out_dir``.

    The folder is written atomically as a whole (:func:`amronet.outputs.files.write_files_atomically`).

    Returns:
        File name → number of rows.

    Raises:
        AmronetError: An unknown format, or Parquet without pyarrow.
    """
    if fmt not in ("csv", "parquet"):
        raise AmronetError(f"--export: unknown format {fmt!r}; choose csv or parquet")
    if fmt == "parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise AmronetError("--export: parquet needs pyarrow; pip install 'amronet[cluster]' "
                               "(or pyarrow), or use --export csv") from None
    files, counts = {}, {}
    for name, (columns, rows) in tables(store, sweep_id).items():
        fname = f"{name}.{fmt}"
        files[fname] = _csv_bytes(rows, columns) if fmt == "csv" else _parquet_bytes(rows, columns)
        counts[fname] = len(rows)
    write_files_atomically(Path(out_dir), files)
    return counts
