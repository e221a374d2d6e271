"""What a worker does with one job: run it and hand back plain data, never raising for a failed run.

Workers (local processes or Dask workers) never touch the result store; the parent process records what they
return, one transaction per run. A batch's runs are handed over one by one as they finish (:func:`report`), not
only when the whole batch ends, so an interrupted sweep keeps every run that finished.

A local pool's worker also never outlives the sweep that started it (:func:`guard_worker`, the pool's
initializer): on Linux the kernel kills it when its parent dies (``prctl(PR_SET_PDEATHSIG, SIGKILL)``), and on
every system a watchdog thread in the worker exits it within a second or so of its parent going away (the
parent's pid gone, or the worker re-parented). So ``kill -9`` of ``amronet sweep`` leaves no idle workers.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import pickle
import signal
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

from amronet.errors import AmronetError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.batch import run_seeds
from amronet.threads import serial_only
from amronet.version import __version__

__all__ = [
    "STARTED",
    "SUMMARY_EXTRAS",
    "execute_batch",
    "execute_job",
    "guard_worker",
    "on_one_thread",
    "one_line_error",
    "pid_alive",
    "report",
    "reporting_to",
    "run_reporting",
    "start_pool_worker",
    "start_worker",
]

SUMMARY_EXTRAS = ("wall_time_s", "amronet_version", "scenario")
"""Summary fields the store keeps in their own columns rather than in the summary JSON (in this order, last)."""


PR_SET_PDEATHSIG = 1
"""``prctl`` option (``<linux/prctl.h>``): the signal the kernel sends this process when its parent dies."""
WATCHDOG_INTERVAL_S = 0.5
"""How often a worker's watchdog looks at its parent."""
STARTED = "job started"
"""What a local pool reports for a job as a worker takes it (:func:`run_reporting`)."""

_sink: Callable[[Any], None] | None = None
"""Where :func:`report` sends items in this process now (``None``: nowhere)."""
_outbox: Any = None
"""A local pool's worker: the pool's channel to its parent, ``(connection, lock)``."""
FRAME = struct.Struct("!Q")
"""The header of a report in the channel: the length of the pickled ``(job, item)`` that follows."""


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this machine and is not a zombie (dead, waiting to be reaped)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # exists, under another user
    except OSError:
        return False
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            state = fh.read().rsplit(b")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True  # no /proc (macOS...): os.kill said it exists
    return state not in (b"Z", b"X")


def _set_parent_death_signal() -> bool:
    """Ask Linux to SIGKILL this process when its parent dies; ``False`` where that is not available."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def guard_worker(parent_pid: int, death_signal: bool = True) -> str:
    """Make this worker process exit when the process that started its pool dies (the pool's initializer).

    Two mechanisms, so that ``kill -9`` of the sweep leaves no worker behind:

    * Linux, ``death_signal``: ``prctl(PR_SET_PDEATHSIG, SIGKILL)``, then the parent is checked once more (it may
      have died between the fork and the ``prctl``). The kernel sends the signal when the *thread* that forked
      the worker ends, so the pool asks for it only when its main thread starts the workers.
    * Everywhere: a daemon thread that checks every :data:`WATCHDOG_INTERVAL_S` seconds whether the worker was
      re-parented (``os.getppid()`` changed) or ``parent_pid`` is gone, and then ends the process with
      ``os._exit``. It covers other systems, pools started by another thread, and the ``forkserver`` start
      method (whose workers are children of the fork server, which ends with the parent).

    Args:
        parent_pid: The pid of the process that owns the pool.
        death_signal: Use the parent-death signal where available.

    Returns:
        ``"pdeathsig+watchdog"`` or ``"watchdog"``: what guards this worker.
    """
    ppid = os.getppid()

    def parent_gone() -> bool:
        return os.getppid() != ppid or (parent_pid != ppid and not pid_alive(parent_pid))

    used = "pdeathsig+watchdog" if death_signal and _set_parent_death_signal() else "watchdog"
    if parent_gone():  # the parent died before the signal was armed
        os._exit(1)

    def watch() -> None:
        while not parent_gone():
            time.sleep(WATCHDOG_INTERVAL_S)
        os._exit(1)

    threading.Thread(target=watch, name="amronet-parent-watchdog", daemon=True).start()
    return used


def start_worker(parent_pid: int, death_signal: bool = True) -> str:
    """A local pool's initializer: kernels on one thread, and no worker outliving the sweep.

    The pool already uses every core (:func:`amronet.threads.serial_only`); :func:`guard_worker` ties the worker to
    the sweep, and its answer is returned.
    """
    serial_only()
    return guard_worker(parent_pid, death_signal)


def start_pool_worker(parent_pid: int, death_signal: bool, outbox: Any) -> str:
    """The initializer of :class:`~amronet.sweeps.executors.LocalExecutor`'s workers: :func:`start_worker`, and more.

    The worker ignores ``SIGINT`` (its parent forked it with the signal blocked; unblocked once ignored): Ctrl-C in
    a terminal reaches every process of the sweep, and the sweep's own process stops its workers itself (it
    terminates them), after recording what they reported. ``outbox`` is the pool's channel to that process,
    ``(connection, lock)`` (:func:`run_reporting`).
    """
    global _outbox
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    _outbox = outbox
    return start_worker(parent_pid, death_signal)


def report(item: Any) -> None:
    """Hand ``item`` (a finished run of a batch) to the process running the sweep now, while the job goes on.

    In a local pool's worker it goes through the pool's channel, and when the job runs in the sweep's own process
    to the executor's callback (:func:`run_reporting`, :func:`reporting_to`); elsewhere (a Dask worker) nowhere:
    the job's result carries it anyway.
    """
    if _sink is not None:
        _sink(item)


@contextlib.contextmanager
def reporting_to(sink: Callable[[Any], None] | None) -> Iterator[None]:
    """Within the block, :func:`report` hands its items to ``sink``."""
    global _sink
    before, _sink = _sink, sink
    try:
        yield
    finally:
        _sink = before


def run_reporting(fn: Callable[[Any], Any], k: int, job: Any, reports: bool = True) -> Any:
    """``fn(job)`` in a local pool's worker, sending ``(k, STARTED)`` and then ``(k, item)`` for each report.

    Each item is written whole into the channel, as one frame (:data:`FRAME`, then the pickle), before this
    returns, so the parent has it before the job's result. Without ``reports`` (nobody reads them)
    :func:`report` sends nothing, and the result carries everything.
    """

    def send(item: Any) -> None:
        connection, lock = _outbox
        data = pickle.dumps((k, item), protocol=pickle.HIGHEST_PROTOCOL)
        frame = memoryview(FRAME.pack(len(data)) + data)
        with lock:
            while frame:
                frame = frame[os.write(connection.fileno(), frame):]

    if _outbox is None or not reports:
        return fn(job)
    send(STARTED)
    with reporting_to(send):
        return fn(job)


def on_one_thread(fn: Callable[[Any], Any], job: Any) -> Any:
    """``fn(job)`` with this process's kernels on one thread: a cluster's workers run one job per core each.

    (:func:`amronet.threads.serial_only`; a Dask worker is a long-lived process that runs only amronet's jobs.)
    """
    serial_only()
    return fn(job)


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


def execute_batch(job: dict[str, Any]) -> list[dict[str, Any] | None]:
    """Run the seeds of one job ``{"scenario": resolved dict, "seeds": [int, ...]}``; one outcome per seed.

    Several seeds of a batchable scenario are stepped together (:class:`~amronet.sim.batch.BatchSimulation`), with
    the same results as one by one; a run's ``wall_time_s`` is then its share of the batch. If the batch raises,
    the seeds not finished yet run again one by one, so every run gets its own outcome (and a failure names its
    own error).

    Each run's outcome is reported as ``(k, outcome)`` (``k``: its place in ``seeds``) as soon as it finishes
    (:func:`report`); where a report reached the sweep's process, the returned list holds ``None`` in its place.
    """
    seeds = [int(s) for s in job["seeds"]]
    outcomes: list[dict[str, Any] | None] = [None] * len(seeds)
    handed: list[bool] = [False] * len(seeds)

    def finished(k: int, outcome: dict[str, Any]) -> None:
        outcomes[k] = outcome
        report((k, outcome))
        handed[k] = _sink is not None

    if len(seeds) > 1:
        out: dict[str, Any] = {"host": socket.gethostname(), "amronet_version": __version__}
        try:

            run_seeds(load_scenario(job["scenario"]), seeds,
                      lambda k, r: finished(k, {**out, **_done(r), "wall_time_s": r.summary["wall_time_s"]}))
        except Exception:
            pass  # the runs not finished again on their own, below, so that each records its own outcome
    for k, seed in enumerate(seeds):
        if outcomes[k] is None:
            finished(k, execute_job({"scenario": job["scenario"], "seed": seed}))
    return [None if sent else outcome for outcome, sent in zip(outcomes, handed, strict=True)]
