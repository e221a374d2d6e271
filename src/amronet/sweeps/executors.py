"""Executors: where jobs run. A local process pool, or a Dask cluster — one interface.

Both take a picklable function and a list of picklable jobs and yield ``(index, result)`` as the jobs finish
(:meth:`Executor.imap_unordered`). An exception raised by the function is re-raised in the caller (the sweep's
worker function never raises for a failed run; see :mod:`amronet.sweeps.worker`). A local worker process that
dies (killed, out of memory) raises :class:`WorkerDiedError`, one line, instead of ``BrokenProcessPool``.

* :class:`LocalExecutor` — ``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes; one worker
  runs the jobs in this process, one after another.
* :class:`DaskExecutor` — a ``distributed.Client`` on an existing scheduler (``tcp://host:8786``; any cluster:
  ``dask scheduler`` + ``dask worker`` by hand, SLURM/PBS through ``dask-jobqueue``, Kubernetes...) or on a
  ``LocalCluster`` it starts. Dask is optional: ``pip install 'amronet[cluster]'``. Losing the scheduler, or
  workers dying under a job, raises :class:`ClusterLostError`, one line, instead of Dask's own exceptions.

:func:`make_executor` picks one from command-line style options.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import logging
import os
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from amronet.errors import AmronetError

__all__ = ["ClusterLostError", "DaskExecutor", "Executor", "LocalExecutor", "WorkerDiedError", "default_workers",
           "make_executor"]

CLUSTER_HINT = "pip install 'amronet[cluster]'"


class WorkerDiedError(AmronetError):
    """A worker process died while running jobs (killed, or out of memory); the pool cannot go on."""

    def __init__(self, message: str = "a worker process died (killed, or out of memory?); run the command "
                                      "again, with fewer --workers if memory is short") -> None:
        super().__init__(message)


class ClusterLostError(AmronetError):
    """The Dask scheduler or its workers went away while jobs ran (connection lost, workers killed)."""

    def __init__(self, cause: str = "the scheduler connection was lost", message: str | None = None) -> None:
        self.cause = cause
        super().__init__(message or f"lost the Dask cluster ({cause}); run the command again once the cluster is "
                                    "back")

    def __reduce__(self) -> tuple[type, tuple[str, str]]:
        return type(self), (self.cause, str(self))


def _lost_cluster_errors() -> tuple[type[BaseException], ...]:
    """What ``distributed`` raises when the scheduler or the workers go away under a running computation."""
    from concurrent.futures import CancelledError as FuturesCancelledError

    errors: list[type[BaseException]] = [FuturesCancelledError, asyncio.CancelledError, OSError, TimeoutError]
    for module, name in (("distributed", "KilledWorker"), ("distributed.client", "FutureCancelledError"),
                         ("distributed.comm.core", "CommClosedError")):
        try:
            errors.append(getattr(importlib.import_module(module), name))
        except (ImportError, AttributeError):
            continue
    return tuple(errors)


def _cause(exc: BaseException) -> str:
    """Why the cluster was lost, in a few words (without Dask's task keys)."""
    reason = getattr(exc, "reason", None)
    if isinstance(reason, str) and reason:
        return reason  # FutureCancelledError: e.g. scheduler-connection-lost
    if type(exc).__name__ == "KilledWorker":
        return "workers died while running a job (out of memory?)"
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


_DASK_LOGGERS = ("distributed.client", "distributed.core", "distributed.utils", "distributed.comm",
                 "distributed.batched", "tornado.application", "asyncio")


class _QuietWhenLost(logging.Filter):
    """Drop Dask's logging about a lost scheduler: :class:`ClusterLostError` says it in one line instead.

    Drops the client's "Failed to reconnect to scheduler" line; once ``lost``, every record (the tracebacks of the
    client's cancelled reconnection as it closes).
    """

    lost = False

    def filter(self, record: logging.LogRecord) -> bool:
        return not self.lost and not str(record.msg).startswith("Failed to reconnect to scheduler")


def default_workers() -> int:
    """Worker processes by default: the cores this process may use."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


class Executor:
    """Runs jobs somewhere and yields their results as they complete."""

    name = "executor"

    @property
    def slots(self) -> int:
        """How many jobs run at once (for the progress bar's *running* count)."""
        raise NotImplementedError

    def imap_unordered(self, fn: Callable[[Any], Any], jobs: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        """Run ``fn(job)`` for every job; yield ``(index, result)`` in the order the jobs finish."""
        raise NotImplementedError

    def describe(self) -> str:
        """One line for the user: where the jobs run."""
        return self.name

    def close(self) -> None:
        """Release the workers."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class LocalExecutor(Executor):
    """A process pool on this machine.

    Args:
        workers: Processes (default: the cores available); 1 runs every job in this process.
    """

    name = "local"

    def __init__(self, workers: int | None = None) -> None:
        if workers is not None and workers < 1:
            raise AmronetError(f"--workers: must be >= 1, got {workers}")
        self.workers = workers or default_workers()
        self._pool: ProcessPoolExecutor | None = None

    @property
    def slots(self) -> int:  # noqa: D102
        return self.workers

    def describe(self) -> str:  # noqa: D102
        return f"local process pool, {self.workers} worker{'s' if self.workers != 1 else ''}"

    def imap_unordered(self, fn: Callable[[Any], Any], jobs: Sequence[Any]) -> Iterator[tuple[int, Any]]:  # noqa: D102
        if self.workers == 1 or len(jobs) <= 1:
            for k, job in enumerate(jobs):
                yield k, fn(job)
            return
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers)
        pending: dict[Future[Any], int] = {}
        try:
            for k, job in enumerate(jobs):
                pending[self._pool.submit(fn, job)] = k
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in sorted(done, key=pending.__getitem__):
                    k = pending.pop(fut)
                    yield k, fut.result()
        except BrokenProcessPool:
            self.close()  # a broken pool runs nothing more; the next call starts a fresh one
            raise WorkerDiedError() from None
        finally:
            for fut in pending:
                fut.cancel()

    def close(self) -> None:  # noqa: D102
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise AmronetError(f"--scheduler/--cluster: Dask is not installed; {CLUSTER_HINT}") from None
    return distributed


class DaskExecutor(Executor):
    """A Dask ``distributed`` cluster: an existing scheduler, or a ``LocalCluster`` started here.

    Args:
        scheduler: Address of a running scheduler (``tcp://host:8786``); ``None`` starts a ``LocalCluster``.
        workers: With a ``LocalCluster``: worker processes (default: the cores available), one thread each.
        timeout: Seconds to wait for the scheduler.

    Raises:
        AmronetError: Dask is not installed, or the scheduler cannot be reached.
    """

    name = "dask"

    def __init__(self, scheduler: str | None = None, workers: int | None = None, timeout: float = 20.0) -> None:
        distributed = _distributed()
        self.scheduler = scheduler
        self.cluster = None
        self._quiet = _QuietWhenLost()
        for name in _DASK_LOGGERS:
            logging.getLogger(name).addFilter(self._quiet)
        try:
            if scheduler is None:
                self.cluster = distributed.LocalCluster(
                    n_workers=workers or default_workers(), threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=logging.ERROR)
                self.client = distributed.Client(self.cluster)
            else:
                self.client = distributed.Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError) as exc:
            self._unquiet()
            if self.cluster is not None:
                self.cluster.close()
            where = scheduler or "a LocalCluster"
            raise AmronetError(f"--scheduler: cannot reach {where}: {str(exc).splitlines()[0]}") from None

    @property
    def slots(self) -> int:  # noqa: D102
        try:
            try:
                info = self.client.scheduler_info(n_workers=-1)
            except TypeError:  # older distributed
                info = self.client.scheduler_info()
        except _lost_cluster_errors() as exc:
            raise ClusterLostError(_cause(exc)) from None
        return max(1, sum(int(w.get("nthreads", 1)) for w in info.get("workers", {}).values()))

    def describe(self) -> str:  # noqa: D102
        where = self.scheduler or "a LocalCluster"
        return f"Dask on {where}, {self.slots} worker thread{'s' if self.slots != 1 else ''}"

    def imap_unordered(self, fn: Callable[[Any], Any], jobs: Sequence[Any]) -> Iterator[tuple[int, Any]]:
        """Run ``fn(job)`` on the cluster for every job; yield ``(index, result)`` as they finish.

        Raises:
            ClusterLostError: The scheduler connection was lost, or workers died under a job (``KilledWorker``).
        """
        distributed = _distributed()
        lost = _lost_cluster_errors()
        futures: list[Any] = []
        try:
            futures = self.client.map(fn, list(jobs), pure=False)
            index = {fut.key: k for k, fut in enumerate(futures)}
            for fut in distributed.as_completed(futures):
                k = index[fut.key]
                result = fut.result()
                fut.release()
                yield k, result
        except lost as exc:
            self._quiet.lost = True
            raise ClusterLostError(_cause(exc)) from None
        finally:
            if not self._quiet.lost:
                with contextlib.suppress(*lost):
                    self.client.cancel([f for f in futures if not f.done()])

    def _unquiet(self) -> None:
        for name in _DASK_LOGGERS:
            logging.getLogger(name).removeFilter(self._quiet)

    def close(self) -> None:
        """Close the client (and the ``LocalCluster`` started here).

        After the cluster was lost the client is closed without waiting long, and Dask's loggers stay quiet about
        it for the rest of the process (its background thread may still log the cancelled reconnection).
        """
        if self._quiet.lost:
            with contextlib.suppress(Exception):
                self.client.close(timeout=2)
        else:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        if not self._quiet.lost:
            self._unquiet()


def make_executor(workers: int | None = None, scheduler: str | None = None, cluster: str | None = None) -> Executor:
    """The executor the options ask for: ``--scheduler ADDRESS``, ``--cluster local`` or a local pool.

    Raises:
        AmronetError: Both ``scheduler`` and ``cluster``, ``workers`` with ``scheduler``, an unknown ``cluster``,
            Dask missing, or an unreachable scheduler.
    """
    if scheduler is not None and cluster is not None:
        raise AmronetError("--scheduler: give either --scheduler ADDRESS or --cluster local, not both")
    if scheduler is not None and workers is not None:
        raise AmronetError("--workers: the workers of --scheduler are the ones started with that scheduler; "
                           "drop --workers (or use --cluster local --workers N)")
    if cluster is not None:
        if cluster != "local":
            raise AmronetError(f"--cluster: only 'local' (a Dask LocalCluster) is built in, got {cluster!r}; "
                               "for another cluster start its scheduler and pass --scheduler ADDRESS")
        return DaskExecutor(workers=workers)
    if scheduler is not None:
        return DaskExecutor(scheduler=scheduler)
    return LocalExecutor(workers)
