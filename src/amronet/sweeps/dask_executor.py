"""The Dask executor: jobs on a ``distributed`` cluster, with one line when the cluster is lost.

:class:`DaskExecutor` is a ``distributed.Client`` on an existing scheduler (``tcp://host:8786``; any cluster:
``dask scheduler`` + ``dask worker`` by hand, SLURM/PBS through ``dask-jobqueue``, Kubernetes...) or on a
``LocalCluster`` it starts. Dask is optional: ``pip install 'amronet[cluster]'``. Losing the scheduler, workers
dying under a job, or no worker at all for ``worker_timeout`` seconds (the scheduler waits for workers forever)
raises :class:`ClusterLostError`, one line, instead of Dask's own exceptions or an endless wait. Leaving the
results early (Ctrl-C) cancels the jobs not finished; a ``LocalCluster`` started here then ends its worker
processes within a second as it closes (Dask cannot stop a running job: the nanny kills its process).
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import importlib
import logging
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from amronet.errors import AmronetError
from amronet.sweeps.executor_base import Executor
from amronet.sweeps.worker import on_one_thread
from amronet.sweeps.worker_bounds import check_worker_timeout, check_workers

__all__ = ["CLUSTER_HINT", "DEFAULT_WORKER_TIMEOUT_S", "STOP_TIMEOUT_S", "ClusterLostError", "DaskExecutor"]

CLUSTER_HINT = "pip install 'amronet[cluster]'"
DEFAULT_WORKER_TIMEOUT_S = 300.0
"""How long a sweep on Dask waits while the scheduler has no worker at all (``--worker-timeout``) before it stops."""
STOP_TIMEOUT_S = 0.5
"""How long an interrupted ``LocalCluster``'s worker processes get to end as it closes."""


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

    Drops the client's "Failed to reconnect to scheduler" and "Couldn't gather ... rescheduling" lines; once
    ``lost``, every record (the tracebacks of the client's cancelled reconnection as it closes).
    """

    lost = False

    def filter(self, record: logging.LogRecord) -> bool:
        # "Couldn't gather N keys, rescheduling": a finished job's worker died; Dask runs the job again (and the
        # sweep gives up after --worker-timeout if no worker is left)
        return not self.lost and not str(record.msg).startswith(("Failed to reconnect to scheduler",
                                                                 "Couldn't gather"))


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
        workers: With a ``LocalCluster``: worker processes (default: the cores available), one thread each; more
            than cores only with ``force``, never more than the memory holds.
        timeout: Seconds to wait for the scheduler.
        worker_timeout: Seconds to wait while the scheduler has no worker at all (all lost, or none started yet)
            before :meth:`imap_unordered` gives up with :class:`ClusterLostError`; ``0`` or ``None`` waits forever.

    Raises:
        AmronetError: Dask is not installed, the scheduler cannot be reached, or ``workers`` is refused.
    """

    name = "dask"

    def __init__(self, scheduler: str | None = None, workers: int | None = None, timeout: float = 20.0,
                 worker_timeout: float | None = DEFAULT_WORKER_TIMEOUT_S, force: bool = False) -> None:
        check_worker_timeout(worker_timeout, dask=True)
        n_workers = check_workers(workers, force) if scheduler is None else None
        distributed = _distributed()
        self.scheduler = scheduler
        self.worker_timeout = worker_timeout
        self.cluster = None
        self._quiet = _QuietWhenLost()
        self._abandoned = False  # jobs were left running (Ctrl-C): close the LocalCluster's workers at once
        for name in _DASK_LOGGERS:
            logging.getLogger(name).addFilter(self._quiet)
        try:
            if scheduler is None:
                self.cluster = distributed.LocalCluster(
                    n_workers=n_workers, threads_per_worker=1, processes=True,
                    dashboard_address=None, silence_logs=logging.ERROR)
                self.client = distributed.Client(self.cluster)
                from amronet.sweeps.dask_plugin import IgnoreInterrupt

                self.client.register_plugin(IgnoreInterrupt())  # Ctrl-C is the sweep's to handle (see close())
            else:
                self.client = distributed.Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError) as exc:
            self._unquiet()
            if self.cluster is not None:
                self.cluster.close()
            where = scheduler or "a LocalCluster"
            raise AmronetError(f"--scheduler: cannot reach {where}: {str(exc).splitlines()[0]}") from None
        except ValueError as exc:  # an address distributed cannot parse: no port, an unknown protocol
            if scheduler is None:
                raise
            self._unquiet()
            raise AmronetError(f"--scheduler: {scheduler!r} is not a scheduler address ({str(exc).splitlines()[0]}); "
                               "give one such as tcp://host:8786") from None

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

        While nothing arrives (no job finishes, or a finished job's result cannot be fetched because its worker
        died and Dask computes it again), the scheduler's workers are counted about every second: with none for
        ``worker_timeout`` seconds (all of them lost; the scheduler would wait for new ones forever) this gives up.

        Raises:
            ClusterLostError: The scheduler connection was lost, workers died under a job (``KilledWorker``), or the
                scheduler had no worker for ``worker_timeout`` seconds.
        """
        distributed = _distributed()
        lost = _lost_cluster_errors()
        futures: list[Any] = []
        watch = _WorkerWatch(self, self.worker_timeout)
        try:
            # a cluster runs one job per core: each job's kernels stay on one thread (amronet.threads)
            futures = self.client.map(functools.partial(on_one_thread, fn), list(jobs), pure=False)
            index = {fut.key: k for k, fut in enumerate(futures)}
            for fut in watch.as_completed(distributed.as_completed(futures)):
                k = index[fut.key]
                result = watch.result(fut)
                fut.release()
                yield k, result
        except ClusterLostError:
            self._quiet.lost = True  # Dask's own complaints about the abandoned jobs, as the client closes
            with contextlib.suppress(*lost):
                self.client.cancel([f for f in futures if not f.done()])
            raise
        except lost as exc:
            self._quiet.lost = True
            raise ClusterLostError(_cause(exc)) from None
        finally:
            left = [f for f in futures if not f.done()]
            self._abandoned = self._abandoned or bool(left)
            if left and not self._quiet.lost:
                with contextlib.suppress(*lost):
                    self.client.cancel(left)

    def worker_count(self) -> int | None:
        """Workers the scheduler knows now; ``None`` when it does not answer within 10 s."""
        try:
            return len(self.client.nthreads(callback_timeout=10))
        except TimeoutError:
            return None

    def _stop_local_workers(self) -> None:
        async def stop() -> None:  # each nanny asks its worker to stop, and kills it after 80 % of the timeout
            await asyncio.gather(*(w.close(timeout=STOP_TIMEOUT_S) for w in list(self.cluster.workers.values())))

        with contextlib.suppress(Exception):  # else the cluster closes them as usual, waiting for their jobs
            self.cluster.sync(stop)

    def _unquiet(self) -> None:
        for name in _DASK_LOGGERS:
            logging.getLogger(name).removeFilter(self._quiet)

    def close(self) -> None:
        """Close the client (and the ``LocalCluster`` started here).

        After the cluster was lost the client is closed without waiting long, and Dask's loggers stay quiet about
        it for the rest of the process (its background thread may still log the cancelled reconnection). A
        ``LocalCluster`` whose jobs were left running ends its workers within about a second (:data:`STOP_TIMEOUT_S`)
        rather than waiting for their jobs.
        """
        if self._abandoned and self.cluster is not None:
            self._stop_local_workers()
        if self._quiet.lost:
            with contextlib.suppress(Exception):
                self.client.close(timeout=2)
        else:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()
        if not self._quiet.lost:
            self._unquiet()


class _WorkerWatch:
    """Waits on Dask futures, but not forever for workers that are gone (see :meth:`DaskExecutor.imap_unordered`).

    Args:
        executor: Whose scheduler to ask for its workers.
        timeout: Seconds without any worker before giving up; ``0`` or ``None``: never.
    """

    POLL_S = 1.0

    def __init__(self, executor: DaskExecutor, timeout: float | None) -> None:
        self.executor = executor
        self.timeout = timeout
        self.workerless_since: float | None = None
        self.next_check = time.monotonic() + self.POLL_S

    def progressed(self) -> None:
        """Something arrived: the cluster works."""
        self.workerless_since, self.next_check = None, time.monotonic() + self.POLL_S

    def check(self) -> None:
        """Count the workers when due; raise when there has been none for ``timeout`` seconds.

        Raises:
            ClusterLostError: No worker for ``timeout`` seconds.
        """
        now = time.monotonic()
        if not self.timeout or now < self.next_check:
            return
        self.next_check = now + self.POLL_S
        count = self.executor.worker_count()
        if count is None:
            return  # the scheduler was slow to answer: nothing learnt
        if count > 0:
            self.workerless_since = None
        elif self.workerless_since is None:
            self.workerless_since = now
        elif now - self.workerless_since >= self.timeout:
            raise ClusterLostError(f"no worker for {self.timeout:g} s; the scheduler is up but all its workers are "
                                   "gone")

    def as_completed(self, finished: Any) -> Iterator[Any]:
        """The futures of ``finished`` (a ``distributed.as_completed``) as they complete."""
        if not self.timeout:
            yield from finished
            return
        condition = getattr(finished, "thread_condition", None)
        while True:
            batch = finished.next_batch(block=False)
            if batch:
                self.progressed()
                yield from batch
                continue
            if finished.is_empty():
                return
            self.check()
            if condition is not None:
                with condition:
                    condition.wait(timeout=0.1)
            else:
                time.sleep(0.05)

    def result(self, future: Any) -> Any:
        """``future.result()``, but not forever for workers that are gone.

        A finished future whose worker died before its result was fetched is computed again by Dask ("Couldn't
        gather ... rescheduling"), which needs a worker.
        """
        if not self.timeout:
            return future.result()
        while True:
            try:
                out = future.result(timeout=self.POLL_S)
            except TimeoutError:
                if future.status == "cancelled":
                    raise
                self.check()  # still on its way (pending again after its worker died): unless no worker is left
                continue
            self.progressed()
            return out
