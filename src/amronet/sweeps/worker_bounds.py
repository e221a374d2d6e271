"""How many worker processes a pool may start: the resource guard of ``--workers`` (:mod:`amronet.limits`).

Every pool amronet starts (:class:`~amronet.sweeps.executors.LocalExecutor`, the ``LocalCluster`` of
:class:`~amronet.sweeps.executors.DaskExecutor`, and so every sweep, figure and plan) asks :func:`check_workers`
first, before any process starts:

* **more workers than cores** are refused unless acknowledged (``--force``, ``force=True``): they would only take
  turns on the cores, each holding its own memory;
* **more workers than the memory holds** are always refused: :data:`~amronet.limits.BYTES_PER_WORKER` each,
  against the memory available now (a run's own memory is its guard's, :mod:`amronet.sim.guard`);
* without ``workers``, the default is the cores, or as many workers as the memory holds when that is fewer.

And a pool never starts more processes than it has jobs (:func:`pool_size`): ``--workers 8`` for 2 runs starts 2.
:func:`check_worker_timeout` checks the other worker option, how long a sweep on Dask waits for workers.
"""

from __future__ import annotations

import os

from amronet import limits
from amronet.errors import AmronetError

__all__ = ["available_cores", "check_worker_timeout", "check_workers", "default_workers", "pool_size"]


def available_cores() -> int:
    """The cores this process may use: its CPU affinity where the system tells it, else the machine's cores."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _fit_in_memory() -> int | None:
    """How many workers the memory available now holds, or ``None`` when the machine does not say."""
    avail = limits.available_memory()
    return None if avail is None else int(avail // limits.BYTES_PER_WORKER)


def default_workers() -> int:
    """Worker processes by default: the cores this process may use, or as many as the memory holds if fewer (>= 1)."""
    fit = _fit_in_memory()
    return max(1, available_cores() if fit is None else min(available_cores(), fit))


def check_workers(workers: int | None, force: bool = False) -> int:
    """The worker processes a pool may start for a requested ``workers`` (``--workers``).

    Args:
        workers: The workers asked for; ``None``: :func:`default_workers`. One worker runs the jobs in this
            process (a local pool) and is never refused.
        force: The user acknowledged more workers than cores (``--force``).

    Returns:
        ``workers``, or the default.

    Raises:
        AmronetError: One line naming ``--workers``: below 1; more than the cores without ``force``; or more
            than the memory available holds, at :data:`~amronet.limits.BYTES_PER_WORKER` each, even with ``force``.
    """
    if workers is None:
        return default_workers()
    if workers < 1:
        raise AmronetError(f"--workers: must be >= 1, got {workers}")
    if workers == 1:
        return 1
    cores = available_cores()
    if workers > cores and not force:
        raise AmronetError(f"--workers: {limits.format_count(workers)} worker processes are more than the {cores} "
                           f"cores this process may use; give --workers {cores} or fewer, or --force to start them "
                           "anyway (force=True in Python)")
    each = limits.format_bytes(limits.BYTES_PER_WORKER)
    limits.check_memory(workers * limits.BYTES_PER_WORKER, "--workers",
                        f"{limits.format_count(workers)} worker processes ({each} each)",
                        f"give --workers {max(_fit_in_memory() or 1, 1)} or fewer (--force does not change this)",
                        error=AmronetError)
    return workers


def pool_size(workers: int, jobs: int) -> int:
    """The processes a pool of ``workers`` starts for ``jobs`` jobs: never more than the jobs (at least 1)."""
    return max(1, min(workers, jobs))


def check_worker_timeout(worker_timeout: float | None, dask: bool) -> None:
    """Check ``--worker-timeout``: at least 0, and only with Dask (``dask``: ``--scheduler`` or ``--cluster``).

    Raises:
        AmronetError: Otherwise.
    """
    if worker_timeout is None:
        return
    if not dask:
        raise AmronetError("--worker-timeout: only with --scheduler ADDRESS or --cluster local (the local pool's "
                           "workers cannot go missing)")
    if not worker_timeout >= 0 or worker_timeout == float("inf"):
        raise AmronetError(f"--worker-timeout: must be a number of seconds >= 0 (0 waits forever), got "
                           f"{worker_timeout}")
