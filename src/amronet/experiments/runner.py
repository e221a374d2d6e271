"""Run many (scenario, seed) jobs on a process pool or a Dask cluster, with a progress bar, in a deterministic order.

Each job is a plain dict (scenario data, seed and labels), so it pickles cheaply; each worker runs it without
writing files and returns the run's summary (and, when asked, its time series). Results come back in job order
whatever the order they finish in.

With a ``store`` (a path, in :class:`~amronet.experiments.options.RunOptions`), the jobs form a sweep of the
result store (:mod:`amronet.sweeps.store`): jobs whose resolved scenario and seed are already done there are
loaded instead of run, and every new run is committed as it finishes, so an interrupted figure resumes where it
stopped.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError
from amronet.experiments.options import RunOptions
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.batch import run_seeds
from amronet.sweeps.engine import execute_into_store, pending_runs, plan_batches, progress_bar, warm_workers
from amronet.sweeps.executors import Executor, LocalExecutor, default_workers
from amronet.sweeps.identity import canonical_json, resolve_scenario, scenario_hash
from amronet.sweeps.local_pool import sigint_elsewhere
from amronet.sweeps.store import ResultStore, check_store_path

__all__ = ["Job", "run_batch", "run_jobs"]

Job = dict[str, Any]
"""``{"scenario": dict, "seed": int, "labels": dict, "timeseries": bool}``."""

_EXECUTION = ("workers", "show_progress", "store", "executor", "retry_failed")
"""The fields of :class:`RunOptions` that :func:`run_jobs` uses (the others shape the jobs, the caller's part)."""


def run_batch(jobs: Sequence[Job]) -> list[dict[str, Any]]:
    """Run jobs of one scenario that differ only in seed and labels, stepped together when the scenario allows.

    Returns:
        One result per job, in order: its labels, seed, summary and (when the job asks) time series, as plain data.
    """
    results = run_seeds(load_scenario(jobs[0]["scenario"]), [job["seed"] for job in jobs])
    outs = []
    for job, result in zip(jobs, results, strict=True):
        out = {"labels": job.get("labels", {}), "seed": job["seed"], "summary": result.summary}
        if job.get("timeseries"):
            out["timeseries"] = {k: v.tolist() for k, v in result.timeseries.items()}
        outs.append(out)
    return outs


def run_jobs(
    jobs: Sequence[Job],
    options: RunOptions | None = None,
    *,
    description: str = "runs",
    on_result: Callable[[int, dict[str, Any]], None] | None = None,
    meanwhile: Callable[[], None] | None = None,
    **changes: Any,
) -> list[dict[str, Any]]:
    """Run jobs, in parallel when there is more than one worker; results in job order.

    Args:
        jobs: The jobs.
        options: How the jobs run: ``workers`` (default: the cores available; 1 runs in this process),
            ``show_progress``, ``store`` (result store to load finished runs from and commit new ones to),
            ``executor`` (default: a local process pool with ``workers`` processes) and ``retry_failed`` (with a
            store, run again the runs it holds as failed; otherwise they stay failed and this raises for them).
            Its ``explorer``, ``time_limit`` and ``seed`` shape the jobs, which the caller has built.
        description: Label of the progress bar (and the sweep's name in the store).
        on_result: Called with ``(index, result)`` as each job finishes (or is loaded from the store).
        meanwhile: Work of this process that needs no result (a figure's static patterns, loading the plotting
            library), called once, in this thread, as the first result arrives: the workers are busy with the
            other jobs by then, so it does not wait for them nor they for it (the results that arrive meanwhile
            are recorded when it returns). Called at the end if no result arrived before.
        **changes: Those five fields of ``options`` to change, for short: ``run_jobs(jobs, workers=1)`` is
            ``run_jobs(jobs, RunOptions(workers=1))``.

    Raises:
        AmronetError: With a store, some runs failed (they are recorded; a call with ``retry_failed`` retries
            them); or a worker process died (:class:`~amronet.sweeps.executors.WorkerDiedError`).
        TypeError: ``changes`` names something else.
    """
    unknown = sorted(set(changes) - set(_EXECUTION))
    if unknown:
        raise TypeError(f"run_jobs() got unexpected keyword arguments {unknown}; it takes {list(_EXECUTION)}")
    options = dataclasses.replace(options or RunOptions(), **changes)
    if jobs:  # fail fast, in this process, on a scenario that cannot start
        Simulation(load_scenario(jobs[0]["scenario"]), jobs[0]["seed"])
    todo = [meanwhile] if meanwhile is not None else []

    def arrived(k: int, result: dict[str, Any]) -> None:
        if on_result is not None:
            on_result(k, result)
        if todo:
            with sigint_elsewhere():  # its kernels run in this process (see amronet.sweeps.local_pool)
                todo.pop()()

    own = options.executor is None
    executor: Executor = options.executor or LocalExecutor(options.workers or default_workers())
    try:
        if options.store is not None:
            results = _run_with_store(jobs, Path(options.store), executor, description, options.show_progress,
                                      arrived, options.retry_failed)
        else:
            results = _run_plain(jobs, executor, description, options.show_progress, arrived)
    finally:
        if own:
            executor.close()
    if todo:
        with sigint_elsewhere():
            todo.pop()()
    return results


def _run_plain(jobs: Sequence[Job], executor: Executor, description: str, show_progress: bool,
               on_result: Callable[[int, dict[str, Any]], None] | None) -> list[dict[str, Any]]:

    results: list[dict[str, Any] | None] = [None] * len(jobs)
    slots = executor.slots if jobs else 0
    batches = plan_batches([(canonical_json(job["scenario"]), job["seed"], job["scenario"]) for job in jobs], slots)
    n = 0
    with progress_bar(show_progress) as bar:
        task = bar.add_task(description, total=len(jobs), done=0, failed=0, running=min(slots, len(jobs)))
        warm_workers(executor, len(jobs), bar, task, description)
        arriving = executor.imap_unordered(run_batch, [[jobs[k] for k in ks] for ks in batches])
        with contextlib.closing(arriving):  # left early (Ctrl-C, an error): the executor stops its workers now
            for b, outs in arriving:
                for k, result in zip(batches[b], outs, strict=True):
                    n += 1
                    results[k] = result
                    if on_result:
                        on_result(k, result)
                    bar.update(task, advance=1, done=n, running=min(slots, len(jobs) - n))
    return [r for r in results if r is not None]


def _run_with_store(jobs: Sequence[Job], store_path: Path, executor: Executor, description: str,
                    show_progress: bool, on_result: Callable[[int, dict[str, Any]], None] | None,
                    retry_failed: bool) -> list[dict[str, Any]]:

    check_store_path(store_path)
    resolved: dict[str, tuple[str, dict[str, Any]]] = {}
    keys = []
    for job in jobs:
        text = canonical_json(job["scenario"])
        if text not in resolved:
            sc = resolve_scenario(load_scenario(job["scenario"]))
            resolved[text] = (scenario_hash(sc), sc)
        keys.append(resolved[text])
    results: list[dict[str, Any] | None] = [None] * len(jobs)
    by_key: dict[tuple[str, int], list[int]] = {}
    for k, ((h, _), job) in enumerate(zip(keys, jobs, strict=True)):
        by_key.setdefault((h, int(job["seed"])), []).append(k)

    def deliver(k: int, loaded: dict[str, Any]) -> None:
        job = jobs[k]
        out = {"labels": job.get("labels", {}), "seed": job["seed"], "summary": loaded["summary"]}
        if job.get("timeseries"):
            out["timeseries"] = loaded["timeseries"]
        results[k] = out
        if on_result:
            on_result(k, out)

    with ResultStore(store_path) as store:
        spec = {"kind": "jobs", "name": description,
                "jobs": [[h, int(job["seed"]), job.get("labels", {})] for (h, _), job in zip(keys, jobs, strict=True)]}
        links = [(h, int(job["seed"]), k, job.get("labels", {})) for k, ((h, _), job) in enumerate(zip(keys, jobs,
                                                                                                      strict=True))]
        store.add_sweep(description, spec, links)
        runs = [(h, int(job["seed"]), sc) for (h, sc), job in zip(keys, jobs, strict=True)]
        pending = pending_runs(store, runs, retry_failed=retry_failed)
        waiting = {(h, s) for h, s, _ in pending}
        stored_failed = set()
        for (h, s), ks in by_key.items():
            if (h, s) not in waiting:
                loaded = store.load(h, s)
                if loaded["status"] != "done":
                    stored_failed.add((h, s))
                    continue
                for k in ks:
                    deliver(k, loaded)

        def arrived(h: str, seed: int, outcome: dict[str, Any]) -> None:
            if outcome["status"] == "done":
                loaded = store.load(h, seed)
                for k in by_key[(h, seed)]:
                    deliver(k, loaded)

        _, failed = execute_into_store(store, pending, executor, description=description,
                                       show_progress=show_progress, total=len(by_key), on_outcome=arrived,
                                       already=(len(by_key) - len(pending) - len(stored_failed),
                                                len(stored_failed)))
        if failed or stored_failed:
            bad = waiting | stored_failed
            errors = [r["error"] for r in store.runs() if r["status"] == "failed" and (r["scenario_hash"],
                                                                                       r["seed"]) in bad]
            retry = "run again to retry them" if retry_failed else "retry them with retry_failed (--retry-failed)"
            raise AmronetError(f"{description}: {failed + len(stored_failed)} of {len(by_key)} runs failed "
                               f"(recorded in {str(store_path)!r}; {retry}); first error: {errors[0]}")
    return [r for r in results if r is not None]
