"""Executors: where jobs run. A local process pool, or a Dask cluster — one interface.

Both take a picklable function and a list of picklable jobs and yield ``(index, result)`` as the jobs finish
(:meth:`Executor.imap_unordered`). An exception raised by the function is re-raised in the caller (the sweep's
worker function never raises for a failed run; see :mod:`amronet.sweeps.worker`). A local worker process that
dies (killed, out of memory) raises :class:`WorkerDiedError`, one line, instead of ``BrokenProcessPool``.

* :class:`LocalExecutor` — ``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes, no more than
  jobs (:mod:`~amronet.sweeps.worker_bounds` bounds ``workers``); one worker runs the jobs in this process, one
  after another. Its workers end when this process dies, even by ``kill -9`` (:func:`~amronet.sweeps.worker.
  guard_worker`: a parent-death signal on Linux, a watchdog thread everywhere); they run their kernels on one
  thread (:func:`amronet.threads.serial_only`). Its jobs report as they go (a batch's runs as each finishes), and
  leaving its results early (Ctrl-C, an error) ends its workers at once (:mod:`~amronet.sweeps.local_pool`).
* :class:`DaskExecutor` (:mod:`~amronet.sweeps.dask_executor`) — a ``distributed.Client`` on an existing scheduler
  or on a ``LocalCluster`` it starts; losing the cluster raises :class:`ClusterLostError`, one line.

The interface is :class:`~amronet.sweeps.executor_base.Executor`; :func:`make_executor` picks one from
command-line style options.
"""

from __future__ import annotations

import contextlib
import functools
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from amronet.errors import AmronetError
from amronet.signals import sigint_deferred
from amronet.sweeps.dask_executor import DEFAULT_WORKER_TIMEOUT_S, ClusterLostError, DaskExecutor
from amronet.sweeps.executor_base import Executor
from amronet.sweeps.local_pool import WorkerPool, sigint_elsewhere
from amronet.sweeps.worker import STARTED, reporting_to
from amronet.sweeps.worker_bounds import check_worker_timeout, check_workers, default_workers, pool_size

__all__ = ["DEFAULT_WORKER_TIMEOUT_S", "ClusterLostError", "DaskExecutor", "Executor", "LocalExecutor",
           "WorkerDiedError", "check_worker_timeout", "default_workers", "make_executor"]

REPORT_POLL_S = 0.05
"""How often a local pool's parent reads its workers' reports while it waits for jobs to finish."""


class WorkerDiedError(AmronetError):
    """A worker process died while running jobs (killed, or out of memory); the pool cannot go on."""

    def __init__(self, message: str = "a worker process died (killed, or out of memory?); run the command "
                                      "again, with fewer --workers if memory is short") -> None:
        super().__init__(message)


class LocalExecutor(Executor):
    """A process pool on this machine.

    Args:
        workers: Processes at most (default: the cores available); 1 runs every job in this process.
        force: Allow more ``workers`` than cores (never more than the memory holds).

    Raises:
        AmronetError: ``workers`` refused by :func:`~amronet.sweeps.worker_bounds.check_workers`.
    """

    name = "local"
    reports = True

    def __init__(self, workers: int | None = None, force: bool = False) -> None:
        self.workers = check_workers(workers, force)
        self.started = 0  # processes of the running pool: at most workers, and at most the jobs it was started for
        self._pool: WorkerPool | None = None
        self._pending: dict[Future[Any], int] = {}  # the jobs of the last imap_unordered not finished yet

    @property
    def slots(self) -> int:  # noqa: D102
        return self.workers

    def describe(self) -> str:  # noqa: D102
        return f"local process pool, {self.workers} worker{'s' if self.workers != 1 else ''}"

    def imap_unordered(self, fn: Callable[[Any], Any], jobs: Sequence[Any],
                       on_report: Callable[[int, Any], None] | None = None) -> Iterator[tuple[int, Any]]:
        """Run ``fn(job)`` for every job; yield ``(index, result)`` in the order the jobs finish.

        ``on_report`` (see :attr:`Executor.reports`) is called in this thread. Leaving early (an exception here or
        in the caller, ``close()`` of this generator) ends the workers at once, their jobs dropped, after passing
        on what they reported; the next call starts a fresh pool.

        Raises:
            WorkerDiedError: A worker process died (killed, out of memory).
        """
        deliver = on_report or (lambda k, item: None)
        if self.workers == 1 or len(jobs) <= 1:
            for k, job in enumerate(jobs):
                deliver(k, STARTED)
                # in this process: a Ctrl-C must not land in a kernel (see amronet.sweeps.local_pool)
                with sigint_elsewhere(), reporting_to(None if on_report is None else functools.partial(on_report, k)):
                    result = fn(job)
                yield k, result
            return
        if self.started < pool_size(self.workers, len(jobs)) or self._pending:
            # none yet, one started for fewer jobs (idle now: a larger one replaces it), or one still running the
            # jobs of a call whose results were left unread (and whose reports would be taken for this call's)
            self.close()
            # the parent-death signal follows the thread that forks the workers: only from the main thread
            death_signal = threading.current_thread() is threading.main_thread()
            self.started = pool_size(self.workers, len(jobs))
            self._pool = WorkerPool(self.started, death_signal)
        pool = self._pool
        pending: dict[Future[Any], int] = {}
        self._pending = pending
        broken = False
        try:
            with sigint_deferred():  # the first submit forks the workers: none sees Ctrl-C before it ignores it
                for k, job in enumerate(jobs):
                    pending[pool.submit(fn, k, job, reports=on_report is not None)] = k
            while pending:
                pool.wait(REPORT_POLL_S)  # a report, or time to look at the jobs
                done, _ = wait(pending, timeout=0, return_when=FIRST_COMPLETED)
                for k, item in pool.reports():  # after `done`: a job finished has all its reports in by now
                    deliver(k, item)
                for fut in sorted(done, key=pending.__getitem__):
                    k = pending.pop(fut)
                    yield k, fut.result()
        except BrokenProcessPool:
            broken = True
            raise WorkerDiedError() from None
        finally:
            if pending or broken:  # left early: nobody wants the rest
                if self._pool is pool:
                    self._pool, self.started = None, 0
                late = pool.stop()
                with contextlib.suppress(Exception):  # the caller is leaving with its own exception
                    for k, item in late:
                        deliver(k, item)

    def close(self) -> None:
        """Release the workers: at once if jobs still run (results left unread), else once they are idle."""
        if self._pool is not None:
            if self._pending:
                self._pool.stop()
            else:
                self._pool.close()
            self._pool, self.started = None, 0


def make_executor(workers: int | None = None, scheduler: str | None = None, cluster: str | None = None,
                  worker_timeout: float | None = None, force: bool = False) -> Executor:
    """The executor the options ask for: ``--scheduler ADDRESS``, ``--cluster local`` or a local pool.

    ``worker_timeout`` (``--worker-timeout``) goes with Dask: how long to wait while the scheduler has no worker
    (default :data:`DEFAULT_WORKER_TIMEOUT_S`; 0 waits forever). ``force`` (``--force``): more workers than cores.

    Raises:
        AmronetError: Both ``scheduler`` and ``cluster``, ``workers`` with ``scheduler``, an unknown ``cluster``,
            ``worker_timeout`` without Dask or below 0, ``workers`` refused (below 1, above the cores without
            ``force``, above the memory), Dask missing, or an unreachable scheduler.
    """
    check_worker_timeout(worker_timeout, dask=scheduler is not None or cluster is not None)
    dask_options = {} if worker_timeout is None else {"worker_timeout": worker_timeout}
    if scheduler is not None and cluster is not None:
        raise AmronetError("--scheduler: give either --scheduler ADDRESS or --cluster local, not both")
    if scheduler is not None and workers is not None:
        raise AmronetError("--workers: the workers of --scheduler are the ones started with that scheduler; "
                           "drop --workers (or use --cluster local --workers N)")
    if cluster is not None:
        if cluster != "local":
            raise AmronetError(f"--cluster: only 'local' (a Dask LocalCluster) is built in, got {cluster!r}; "
                               "for another cluster start its scheduler and pass --scheduler ADDRESS")
        return DaskExecutor(workers=workers, force=force, **dask_options)
    if scheduler is not None:
        return DaskExecutor(scheduler=scheduler, **dask_options)
    return LocalExecutor(workers, force)
