"""Running the missing runs of a sweep on an executor, recording each in the store as it finishes.

:func:`run_sweep` is ``amronet sweep``; :func:`execute_into_store` is the loop it shares with
:func:`amronet.experiments.runner.run_jobs` (the paper's figures): submit the runs that are not in the store
yet, record every outcome in its own transaction as it arrives (a batch's runs one by one, as each finishes),
and draw a progress bar (done / running / failed, elapsed, ETA) on stderr. Ctrl-C stops the workers at once and
raises :class:`~amronet.sweeps.interrupt.SweepInterrupted`, which says what the store holds.
"""

from __future__ import annotations

import contextlib
import itertools
import os
import sqlite3
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from amronet.scenario import load_scenario
from amronet.sim.batch import batchable
from amronet.sim.warmup import warm_up_if_cold
from amronet.sweeps.executors import ClusterLostError, Executor, LocalExecutor, WorkerDiedError
from amronet.sweeps.interrupt import interrupted
from amronet.sweeps.spec import Sweep
from amronet.sweeps.store import ClaimOwner, ResultStore, StoreError
from amronet.sweeps.worker import STARTED, execute_batch, start_worker
from amronet.sweeps.worker_bounds import pool_size

if TYPE_CHECKING:
    from rich.progress import TaskID

    from amronet.sweeps.store import RunKey

__all__ = ["CLAIM_POLL_S", "MAX_BATCH", "SweepReport", "execute_into_store", "pending_runs", "plan_batches",
           "run_sweep", "warm_workers"]

StoreJob = tuple[str, int, dict[str, Any]]
"""``(scenario_hash, seed, resolved scenario)``."""

MAX_BATCH = 16
"""Most runs in one batch job. Per-run cost hardly falls beyond this (30 robots: 34 us per run-step at 10 runs,
31 us at 25, against 115 us alone), while smaller batches share the work out more evenly and lose less when a
sweep is interrupted (the runs of a batch still going are dropped)."""
CLAIM_POLL_S = 0.5
"""How often a sweep looks again at runs that another process on the same store has claimed."""


@dataclass
class SweepReport:
    """What one invocation of a sweep did.

    Attributes:
        sweep_id: The sweep's id in the store.
        total: Runs in the sweep.
        already: Runs found in the store (done, or failed and not retried) before starting.
        done: Runs that finished now (computed by this invocation).
        failed: Runs that raised now.
        wall_time_s: Seconds this invocation took.
        executor: Where the runs ran.
        elsewhere: Runs that another process (a sweep on the same store at the same time) recorded while this one
            ran: they were claimed by it, so not computed here.
    """

    sweep_id: int
    total: int
    already: int
    done: int
    failed: int
    wall_time_s: float
    executor: str
    elsewhere: int = 0


def progress_bar(show: bool) -> Progress:
    """The progress bar of sweeps and figures: bar, done / running / failed, elapsed, ETA (on stderr)."""
    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("[green]{task.fields[done]} done[/] [cyan]{task.fields[running]} running[/] "
                          "[red]{task.fields[failed]} failed[/]"),
               TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn())
    return Progress(*columns, console=Console(stderr=True), disable=not show, transient=False)


def pending_runs(store: ResultStore, runs: Sequence[StoreJob], retry_failed: bool) -> list[StoreJob]:
    """The runs that still have to run: not in the store, or failed when ``retry_failed``."""
    statuses = store.statuses()
    out, seen = [], set()
    for h, seed, scenario in runs:
        status = statuses.get((h, seed))
        if (h, seed) in seen or status == "done" or (status == "failed" and not retry_failed):
            continue
        seen.add((h, seed))
        out.append((h, seed, scenario))
    return out


def plan_batches(pending: Sequence[StoreJob], slots: int, max_size: int = MAX_BATCH) -> list[list[int]]:
    """Group runs into jobs: runs of one batchable scenario (:func:`amronet.sim.batch.batchable`) share a job.

    A scenario's ``n`` runs form ``max(ceil(n / max_size), min(slots, n))`` batches of nearly equal size, so
    that every slot gets work; any other run is a job of its own. Larger jobs come first (they take longest).

    Returns:
        Lists of indices into ``pending``, one per job.
    """
    by_hash: dict[str, list[int]] = {}
    for k, (h, _, _) in enumerate(pending):
        by_hash.setdefault(h, []).append(k)
    jobs: list[list[int]] = []
    for ks in by_hash.values():
        try:
            together = len(ks) > 1 and batchable(load_scenario(pending[ks[0]][2]))
        except Exception:
            together = False  # not this function's business: the run itself reports it
        if not together:
            jobs += [[k] for k in ks]
            continue
        parts = max(-(-len(ks) // max_size), min(slots, len(ks)))
        size, extra = divmod(len(ks), parts)
        at = 0
        for p in range(parts):
            n = size + (p < extra)
            jobs.append(ks[at:at + n])
            at += n
    jobs.sort(key=len, reverse=True)  # stable: equal sizes keep the runs' order
    return jobs


def execute_into_store(
    store: ResultStore,
    pending: Sequence[StoreJob],
    executor: Executor,
    description: str = "runs",
    show_progress: bool = True,
    total: int | None = None,
    on_outcome: Callable[[str, int, dict[str, Any]], None] | None = None,
    already: tuple[int, int] = (0, 0),
) -> tuple[int, int]:
    """Run ``pending`` on ``executor`` and record each outcome in ``store`` as soon as it arrives.

    Every run is claimed in the store before it is submitted (:meth:`~amronet.sweeps.store.ResultStore.claim`),
    so that another process running a sweep on the same store at the same time never computes it too: runs
    claimed by a live other process are waited for (polling the store every :data:`CLAIM_POLL_S` s) and taken over
    when their claim turns stale (that process died). A run another process records meanwhile counts as finished
    here, with the outcome ``{"status": ..., "elsewhere": True}`` for ``on_outcome``.

    Args:
        store: The open store.
        pending: The runs to run.
        executor: Where they run.
        description: Label of the progress bar.
        show_progress: Draw the progress bar.
        total: Runs in the whole sweep (the bar starts at ``total - len(pending)``); default ``len(pending)``.
        on_outcome: Called with ``(scenario_hash, seed, outcome)`` after each run is recorded.
        already: ``(done, failed)`` runs of the sweep found in the store, for the bar's counts.

    Returns:
        ``(done, failed)`` among ``pending`` (with those another process finished meanwhile).

    Raises:
        SweepInterrupted: Ctrl-C (``KeyboardInterrupt``): the workers were stopped (a local pool's at once), the
            runs that finished are in the store, and the message counts them, those dropped and those not started.
        WorkerDiedError: A local worker process died (killed, out of memory); the runs recorded so far stay in the
            store, so running the same command again resumes.
        ClusterLostError: The Dask scheduler connection was lost, workers died under a job, or the scheduler had no
            worker for the executor's ``worker_timeout``; likewise.
    """
    total = len(pending) if total is None else total
    remaining: dict[tuple[str, int], StoreJob] = {}
    for run in pending:
        remaining.setdefault((run[0], int(run[1])), run)
    versions = store.versions()
    seen = {key: versions.get(key) for key in remaining}
    owner = ClaimOwner.new()
    counts = [0, 0]  # done, failed
    claimed = False
    pending_keys, in_flight, recorded = list(remaining), set(), set()  # in_flight: being computed now

    def count(h: str, seed: int, outcome: dict[str, Any]) -> None:
        recorded.add((h, int(seed)))
        counts[outcome["status"] != "done"] += 1
        bar.update(task, advance=1, done=already[0] + counts[0], failed=already[1] + counts[1])
        if on_outcome is not None:
            on_outcome(h, seed, outcome)

    keep_alive = store.heartbeat(owner) if remaining else contextlib.nullcontext()
    with progress_bar(show_progress) as bar, keep_alive:
        task = bar.add_task(description, total=total, completed=total - len(pending), done=already[0],
                            failed=already[1], running=0)
        try:
            while remaining:
                claims = store.claim(list(remaining), owner, seen)
                claimed = claimed or bool(claims.claimed)
                for key, status in claims.finished.items():
                    h, seed, _ = remaining.pop(key)
                    count(h, seed, {"status": status, "elsewhere": True})
                if claims.claimed:
                    bar.update(task, description=description)
                    claimed_runs = [remaining.pop(key) for key in claims.claimed]
                    _run_claimed(store, claimed_runs, executor, (bar, task, description), count, in_flight)
                elif remaining:
                    holders = ", ".join(sorted(set(claims.held.values())))
                    bar.update(task, running=0, description=f"{description} (waiting for {len(claims.held)} runs "
                                                            f"claimed by {holders})")
                    time.sleep(CLAIM_POLL_S)
        except KeyboardInterrupt:
            raise interrupted(store, total, pending_keys, seen, in_flight, recorded) from None
        except WorkerDiedError:
            raise WorkerDiedError(f"a worker process died (killed, or out of memory?); the finished runs are kept in "
                             f"{str(store.path)!r}: run the same command again to resume (with fewer --workers if "
                             "memory is short)") from None
        except ClusterLostError as exc:
            raise ClusterLostError(exc.cause,
                f"lost the Dask cluster ({exc.cause}); the finished runs are in {str(store.path)!r}: run the same "
                "command again to resume") from None
        finally:
            if claimed:
                with contextlib.suppress(sqlite3.Error, StoreError):
                    store.release(owner)  # runs claimed but not recorded (interrupted): free for the next sweep now
    return counts[0], counts[1]


def warm_workers(executor: Executor, runs: int, bar: Progress, task: TaskID, description: str) -> None:
    """Before ``runs`` runs on a local process pool, compile the kernels they share across its workers if needed.

    Needed: this version of amronet's kernels was never compiled (:func:`~amronet.sim.warmup.warm_up_if_cold`);
    the progress bar says so meanwhile. Other executors' workers are on other machines, with caches of their own.
    """
    if not isinstance(executor, LocalExecutor):
        return

    def announce() -> None:
        bar.update(task, description=f"{description} (compiling amronet's kernels: once per version)")

    # like the pool's workers: none outlives this process
    guard = (os.getpid(), threading.current_thread() is threading.main_thread())
    if warm_up_if_cold(pool_size(executor.workers, runs), runs, announce, start_worker, guard) is not None:
        bar.update(task, description=description)


def _run_claimed(store: ResultStore, runs: Sequence[StoreJob], executor: Executor,
                 progress: tuple[Progress, TaskID, str], count: Callable[[str, int, dict[str, Any]], None],
                 in_flight: set[RunKey]) -> None:
    """Run ``runs`` (claimed) on ``executor`` in batches, recording each outcome as it arrives.

    ``in_flight`` holds the runs being computed meanwhile: the runs not recorded yet of the batches that started
    (an executor that :attr:`~amronet.sweeps.executor_base.Executor.reports` says when), or else of the first
    ``slots`` batches not finished.
    """
    bar, task, description = progress
    slots = executor.slots
    reports = getattr(executor, "reports", False)
    batches = plan_batches(runs, slots)
    jobs = [{"scenario": runs[ks[0]][2], "seeds": [runs[k][1] for k in ks]} for ks in batches]
    todo = {b: {(runs[k][0], int(runs[k][1])) for k in ks} for b, ks in enumerate(batches)}  # in submission order

    def flying() -> None:
        if not reports:
            in_flight.clear()
            in_flight.update(*itertools.islice(todo.values(), slots))
        bar.update(task, running=len(in_flight))

    def record(b: int, k: int, outcome: dict[str, Any]) -> None:
        h, seed, scenario = runs[k]
        store.record(h, seed, scenario, outcome)
        todo.get(b, set()).discard((h, int(seed)))
        in_flight.discard((h, int(seed)))
        flying()
        count(h, seed, outcome)

    def on_report(b: int, item: Any) -> None:
        if item == STARTED:
            in_flight.update(todo.get(b, ()))
            flying()
        else:
            record(b, batches[b][item[0]], item[1])

    warm_workers(executor, len(runs), bar, task, description)
    flying()
    results = (executor.imap_unordered(execute_batch, jobs, on_report=on_report) if reports
               else executor.imap_unordered(execute_batch, jobs))
    try:
        for b, outcomes in results:
            for k, outcome in zip(batches[b], outcomes, strict=True):
                if outcome is not None:  # None: reported and recorded as it finished
                    record(b, k, outcome)
            del todo[b]
            flying()
    finally:
        close = getattr(results, "close", None)
        if close is not None:
            close()  # left early (Ctrl-C, an error): the executor stops the workers now


def run_sweep(
    sweep: Sweep,
    store_path: str | Path,
    executor: Executor | None = None,
    retry_failed: bool = False,
    show_progress: bool = True,
) -> SweepReport:
    """Run every (point, seed) of ``sweep`` that is not in the store yet.

    Args:
        sweep: A validated sweep (:func:`~amronet.sweeps.spec.load_sweep`).
        store_path: The result store (created when missing).
        executor: Where the runs run (default: a local process pool on every core).
        retry_failed: Run again the runs recorded as failed.
        show_progress: Draw a progress bar on stderr.

    Returns:
        A :class:`SweepReport`.

    Raises:
        StoreError: The store path is not an amronet store.
        WorkerDiedError: A local worker process died; the finished runs are in the store, run again to resume.
        ClusterLostError: The Dask cluster was lost; likewise.

    Another process may run a sweep on the same store at the same time: each run is computed by one of them (see
    :func:`execute_into_store`), and each returns once every run of its sweep is in the store.
    """
    start = time.perf_counter()
    own = executor is None
    executor = executor or LocalExecutor()
    runs = sweep.runs()
    try:
        with ResultStore(store_path) as store:
            spec = sweep.spec.model_dump(mode="json")
            links = [(p.hash, seed, p.index, p.overrides) for p, seed in runs]
            sweep_id = store.add_sweep(sweep.name, spec, links)
            pending = pending_runs(store, [(p.hash, seed, p.scenario) for p, seed in runs], retry_failed)
            statuses, waiting = store.statuses(), {(h, s) for h, s, _ in pending}
            before = [statuses[(p.hash, s)] for p, s in runs if (p.hash, s) not in waiting]
            elsewhere = [0, 0]

            def by_others(h: str, seed: int, outcome: dict[str, Any]) -> None:
                if outcome.get("elsewhere"):
                    elsewhere[outcome["status"] != "done"] += 1

            done, failed = execute_into_store(store, pending, executor, description=sweep.name,
                                              show_progress=show_progress, total=len(runs), on_outcome=by_others,
                                              already=(before.count("done"), before.count("failed")))
        where = executor.describe()
    finally:
        if own:
            executor.close()
    return SweepReport(sweep_id=sweep_id, total=len(runs), already=len(runs) - len(pending),
                       done=done - elsewhere[0], failed=failed - elsewhere[1],
                       wall_time_s=time.perf_counter() - start, executor=where, elsewhere=sum(elsewhere))
