"""Run many (scenario, seed) jobs on a local process pool, with a progress bar, in a deterministic order.

Each job is a plain dict (scenario data, seed and labels), so it pickles cheaply; each worker runs it without
writing files and returns the run's summary (and, when asked, its time series). Results come back in job order
whatever the order they finish in.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any

from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

__all__ = ["Job", "run_jobs"]

Job = dict[str, Any]
"""``{"scenario": dict, "seed": int, "labels": dict, "timeseries": bool}``."""


def run_job(job: Job) -> dict[str, Any]:
    """Run one job and return its labels, summary and (optionally) time series as plain data."""
    from amronet.scenario import load_scenario
    from amronet.sim import Simulation

    result = Simulation(load_scenario(job["scenario"]), job["seed"]).run()
    out = {"labels": job.get("labels", {}), "seed": job["seed"], "summary": result.summary}
    if job.get("timeseries"):
        out["timeseries"] = {k: v.tolist() for k, v in result.timeseries.items()}
    return out


def default_workers() -> int:
    """Worker processes by default: the cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def run_jobs(
    jobs: Sequence[Job],
    workers: int | None = None,
    description: str = "runs",
    show_progress: bool = True,
    on_result: Callable[[int, dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Run jobs, in parallel when ``workers > 1``; results in job order.

    Args:
        jobs: The jobs.
        workers: Worker processes (default: the cores available); 1 runs in this process.
        description: Label of the progress bar.
        show_progress: Draw a progress bar (on stderr).
        on_result: Called with ``(index, result)`` as each job finishes.
    """
    workers = workers or default_workers()
    if jobs:  # fail fast, in this process, on a scenario that cannot start
        from amronet.scenario import load_scenario
        from amronet.sim import Simulation

        Simulation(load_scenario(jobs[0]["scenario"]), jobs[0]["seed"])
    results: list[dict[str, Any] | None] = [None] * len(jobs)
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
               TextColumn("eta"), TimeRemainingColumn())
    with Progress(*columns, disable=not show_progress, transient=False) as progress:
        task = progress.add_task(description, total=len(jobs))
        if workers == 1 or len(jobs) <= 1:
            for k, job in enumerate(jobs):
                results[k] = run_job(job)
                if on_result:
                    on_result(k, results[k])
                progress.advance(task)
        else:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futures = {pool.submit(run_job, job): k for k, job in enumerate(jobs)}
                for fut in as_completed(futures):
                    k = futures[fut]
                    results[k] = fut.result()
                    if on_result:
                        on_result(k, results[k])
                    progress.advance(task)
    return [r for r in results if r is not None]
