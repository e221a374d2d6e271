"""The pool of :class:`~amronet.sweeps.executors.LocalExecutor`: worker processes that report and stop at once.

A ``concurrent.futures.ProcessPoolExecutor`` runs the jobs. Beside it a pipe carries what a job reports while it
runs (:func:`amronet.sweeps.worker.report`: each run of a batch as it finishes), which the parent reads as it
waits for jobs (:meth:`WorkerPool.wait`, :meth:`WorkerPool.reports`), so a finished run is stored before its batch
ends. The parent never blocks on the pipe: it reads what is there and unpickles the complete frames only, so a
worker that dies half-way through a report (killed, out of memory) cannot hang it.

The workers ignore ``SIGINT`` (:func:`~amronet.sweeps.worker.start_pool_worker`; it is blocked from the fork until
then, :func:`amronet.signals.sigint_deferred`): Ctrl-C in a terminal reaches every process of the sweep, and it is
the parent that ends them, with :meth:`WorkerPool.stop` — ``SIGTERM``, then ``SIGKILL`` after
:data:`STOP_GRACE_S` — instead of waiting for their jobs. It then reads the reports they completed before they
ended (a report cut short is dropped).
The pool's own futures are never cancelled here: only ``shutdown(cancel_futures=True)`` cancels them (Python 3.11's
pool hangs when a worker dies after a future was cancelled by hand).

Jobs run in the sweep's own process (one worker, or one job) do so within :func:`sigint_elsewhere`: a ``SIGINT``
delivered to a thread inside a numba kernel crashes the process at times (a segmentation fault, numba issue
#2324), so that thread blocks it and an idle thread takes it; Python still raises ``KeyboardInterrupt`` in the
main thread as soon as the kernel returns.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from multiprocessing.connection import wait as wait_for
from typing import Any

from amronet.signals import sigint_deferred
from amronet.sweeps.worker import FRAME, run_reporting, start_pool_worker

__all__ = ["STOP_GRACE_S", "WorkerPool", "sigint_elsewhere"]

STOP_GRACE_S = 0.5
"""How long a worker has to end after ``SIGTERM`` before :meth:`WorkerPool.stop` kills it."""


def _take_sigint() -> None:
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    threading.Event().wait()


_receiver: threading.Thread | None = None
"""The idle thread that takes ``SIGINT`` within :func:`sigint_elsewhere`."""


@contextlib.contextmanager
def sigint_elsewhere() -> Iterator[None]:
    """Within the block (in the main thread), Ctrl-C is delivered to an idle thread, not to this one.

    For numba kernels run in this thread (see the module docstring); ``KeyboardInterrupt`` is still raised here,
    once the running kernel returns (a stretch of steps: milliseconds). Elsewhere than in the main thread, or
    without ``pthread_sigmask``, nothing changes.
    """
    global _receiver
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    if _receiver is None or not _receiver.is_alive():
        _receiver = threading.Thread(target=_take_sigint, name="amronet-sigint", daemon=True)
        _receiver.start()
    with sigint_deferred():
        yield


class WorkerPool:
    """``processes`` worker processes with a channel for their reports (see the module docstring).

    Args:
        processes: How many.
        death_signal: Arm the parent-death signal in each (:func:`~amronet.sweeps.worker.guard_worker`).
    """

    def __init__(self, processes: int, death_signal: bool) -> None:
        ctx = multiprocessing.get_context()
        self.processes = processes
        self._reader, self._writer = ctx.Pipe(duplex=False)
        os.set_blocking(self._reader.fileno(), False)
        self._inbox = bytearray()  # bytes read, not unpickled yet: the start of a frame still being written
        outbox = (self._writer, ctx.Lock())
        self._pool = ProcessPoolExecutor(max_workers=processes, mp_context=ctx, initializer=start_pool_worker,
                                         initargs=(os.getpid(), death_signal, outbox))

    def submit(self, fn: Callable[[Any], Any], k: int, job: Any, reports: bool = True) -> Future[Any]:
        """Run ``fn(job)`` as job ``k``, whose reports arrive as ``(k, item)`` if ``reports``.

        (:func:`~amronet.sweeps.worker.run_reporting`.) The first call starts the workers: call it within
        :func:`sigint_deferred`.
        """
        return self._pool.submit(run_reporting, fn, k, job, reports)

    def pids(self) -> list[int]:
        """The worker processes' pids (none before the first :meth:`submit`)."""
        return [process.pid for process in self._processes()]

    def _processes(self) -> list[Any]:
        # the attribute CPython's own terminate_workers() (Python 3.14) reads: the running worker processes
        return list(dict(getattr(self._pool, "_processes", None) or {}).values())

    def wait(self, timeout: float) -> None:
        """Wait until a report arrives, at most ``timeout`` seconds."""
        wait_for([self._reader], timeout)

    def reports(self) -> list[tuple[int, Any]]:
        """The reports that have arrived, without waiting; a job's reports all arrive before its result."""
        with contextlib.suppress(BlockingIOError):
            while chunk := os.read(self._reader.fileno(), 1 << 20):
                self._inbox += chunk
        out = []
        while len(self._inbox) >= FRAME.size:
            end = FRAME.size + FRAME.unpack_from(self._inbox)[0]
            if len(self._inbox) < end:
                break
            out.append(pickle.loads(self._inbox[FRAME.size:end]))
            del self._inbox[:end]
        return out

    def stop(self) -> list[tuple[int, Any]]:
        """End every worker now, whatever it runs, and return the complete reports not read yet.

        Returns within about ``2 * STOP_GRACE_S`` seconds; the pool's futures not finished fail or are cancelled.
        Once stopped, the pool stays so (this returns nothing more).
        """
        if self._reader.closed:
            return []
        processes = self._processes()
        self._pool.shutdown(wait=False, cancel_futures=True)
        sentinels = {}
        for process in processes:
            with contextlib.suppress(ValueError, OSError):  # not started, or already reaped
                sentinels[process.sentinel] = process
                process.terminate()
        left = list(sentinels)
        deadline = time.monotonic() + STOP_GRACE_S
        while left and (rest := deadline - time.monotonic()) > 0:
            ended = set(wait_for(left, rest))
            left = [s for s in left if s not in ended]
        for s in left:
            with contextlib.suppress(ValueError, OSError):
                sentinels[s].kill()
        if left:
            wait_for(left, STOP_GRACE_S)
        late = []
        with contextlib.suppress(Exception):
            late = self.reports()  # a report cut short by the end of its worker stays unread
        self._writer.close()
        self._reader.close()
        return late

    def close(self) -> None:
        """Shut the pool down once its jobs have ended (the idle workers exit)."""
        if self._reader.closed:
            return
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._writer.close()
        self._reader.close()
