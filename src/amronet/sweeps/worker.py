"""What a worker does with one job: run it and hand back plain data, never raising for a failed run.

Workers (local processes or Dask workers) never touch the result store; the parent process records what they
return, one transaction per run.
"""

from __future__ import annotations

import socket
import time
from typing import Any

from amronet import __version__
from amronet.errors import AmronetError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.batch import run_seeds

__all__ = ["SUMMARY_EXTRAS", "execute_batch", "execute_job", "one_line_error"]

SUMMARY_EXTRAS = ("wall_time_s", "amronet_version", "scenario")
"""Summary fields the store keeps in their own columns rather than in the summary JSON (in this order, last)."""


def one_line_error(exc: BaseException) -> str:
    """An exception as one line: ``Type: first line of the message`` (just the message for amronet's own)."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, AmronetError):
        return text or type(exc).__name__
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def execute_job(job: dict[str, Any]) -> dict[str, Any]:
    """Run one job ``{"scenario": resolved dict, "seed": int}`` and return its outcome as plain data.

    Returns:
        ``{"status": "done", "summary", "timeseries", "wall_time_s", "host", "amronet_version"}`` (the summary
        without :data:`SUMMARY_EXTRAS`; the time series as lists) or ``{"status": "failed", "error": one line,
        ...}`` when the run raised.
    """
    start = time.perf_counter()
    out: dict[str, Any] = {"host": socket.gethostname(), "amronet_version": __version__}
    try:

        result = Simulation(load_scenario(job["scenario"]), int(job["seed"])).run()
    except Exception as exc:
        return {**out, "status": "failed", "error": one_line_error(exc), "summary": None, "timeseries": None,
                "wall_time_s": time.perf_counter() - start}
    return {**out, **_done(result), "wall_time_s": time.perf_counter() - start}


def _done(result: Any) -> dict[str, Any]:
    summary = {k: v for k, v in result.summary.items() if k not in SUMMARY_EXTRAS}
    timeseries = {k: v.tolist() for k, v in result.timeseries.items()}
    return {"status": "done", "error": None, "summary": summary, "timeseries": timeseries}


def execute_batch(job: dict[str, Any]) -> list[dict[str, Any]]:
    """Run the seeds of one job ``{"scenario": resolved dict, "seeds": [int, ...]}``; one outcome per seed.

    Several seeds of a batchable scenario are stepped together (:class:`~amronet.sim.batch.BatchSimulation`), with
    the same results as one by one; a run's ``wall_time_s`` is then its share of the batch. If the batch raises,
    its seeds run again one by one, so every run gets its own outcome (and a failure names its own error).
    """
    seeds = [int(s) for s in job["seeds"]]
    if len(seeds) > 1:
        out: dict[str, Any] = {"host": socket.gethostname(), "amronet_version": __version__}
        try:

            results = run_seeds(load_scenario(job["scenario"]), seeds)
        except Exception:
            pass  # each run again on its own, below, so that it records its own outcome
        else:
            return [{**out, **_done(r), "wall_time_s": r.summary["wall_time_s"]} for r in results]
    return [execute_job({"scenario": job["scenario"], "seed": seed}) for seed in seeds]
