"""Executors: where jobs run. A local process pool, or a Dask cluster — one interface.

Both take a picklable function and a list of picklable jobs and yield ``(index, result)`` as the jobs finish
(:meth:`Executor.imap_unordered`). An exception raised by the function is re-raised in the caller (the sweep's
worker function never raises for a failed run; see :mod:`amronet.sweeps.worker`). A local worker process that
dies (killed, out of memory) raises :class:`WorkerDiedError`, one line, instead of ``BrokenProcessPool``.

* :class:`LocalExecutor` — ``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes, no more than
  jobs (:mod:`~amronet.sweeps.worker_bounds` bounds ``workers``); one worker runs the jobs in this process, one
  after another. Its workers end when this process dies, even by ``kill -9`` (:func:`~amronet.sweeps.worker.
  guard_worker`: a parent-death signal on Linux, a watchdog thread everywhere); they run their kernels on one
  thread (:func:`amronet.threads.serial_only`).
* :class:`DaskExecutor` (:mod:`~amronet.sweeps.dask_executor`) — a ``distributed.Client`` on an existing scheduler
  or on a ``LocalCluster`` it starts; losing the cluster raises :class:`ClusterLostError`, one line.

The interface is :class:`~amronet.sweeps.executor_base.Executor`; :func:`make_executor` picks one from
command-line style options.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from amronet.errors import AmronetError
from amronet.sweeps.dask_executor import DEFAULT_WORKER_TIMEOUT_S, ClusterLostError, DaskExecutor
from amronet.sweeps.executor_base import Executor
from amronet.sweeps.worker import start_worker
from amronet.sweeps.worker_bounds import check_worker_timeout, check_workers, default_workers, pool_size

__all__ = ["DEFAULT_WORKER_TIMEOUT_S", "ClusterLostError", "DaskExecutor", "Executor", "LocalExecutor",
           "WorkerDiedError", "check_worker_timeout", "default_workers", "make_executor"]


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

    def __init__(self, workers: int | None = None, force: bool = False) -> None:
        self.workers = check_workers(workers, force)
        self.started = 0  # processes of the running pool: at most workers, and at most the jobs it was started for
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
        if self.started < pool_size(self.workers, len(jobs)):
            self.close()  # none yet, or one started for fewer jobs (idle now): a larger one replaces it
            # the parent-death signal follows the thread that forks the workers: only from the main thread
            death_signal = threading.current_thread() is threading.main_thread()
            self.started = pool_size(self.workers, len(jobs))
            self._pool = ProcessPoolExecutor(max_workers=self.started, initializer=start_worker,
                                             initargs=(os.getpid(), death_signal))
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
