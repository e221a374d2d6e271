"""When amronet's kernels use more than one core: large runs only, on a thread pool that survives ``fork``.

A step of a few thousand robots takes a few milliseconds, less than handing work to other threads is worth,
and a sweep already keeps every core busy with one run per worker process. A run of tens of thousands of robots
is different: its neighbour search and the sensing, deciding and obstacle checks of its self-spreading step take
tens of milliseconds, spent row by row and robot by robot on independent data. Those have threaded twins
(``prange`` over rows or robots: :func:`amronet.engine.neighbours.neighbour_csr_checked`,
:class:`amronet.algorithms.self_spreading.fast.CompiledSpreading`) that give the same numbers bit for bit; a caller
picks one
with :func:`use_threads`, which says yes only when

* the call handles at least :data:`MIN_ITEMS` points or robots,
* this process may use threads (:func:`serial_only` was not called: a sweep's worker processes call it, and every
  job on a Dask cluster: they already run one run per core), and
* numba has more than one thread (``NUMBA_NUM_THREADS``, by default the number of cores).

numba's thread pool comes in three kinds. The GNU OpenMP one that numba picks first on Linux is not safe to
``fork`` (a child forked after its parent used it is killed when it uses it), and amronet's sweeps fork their
workers, so :func:`configure` asks numba for a fork-safe pool (``forksafe``: Intel TBB where it is installed,
else numba's own ``workqueue``), unless the user chose one with ``NUMBA_THREADING_LAYER``. ``workqueue`` must not
be entered by two Python threads at once; callers hold :data:`LOCK` while a threaded kernel runs.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Iterator

import numba

__all__ = ["LOCK", "MIN_ITEMS", "configure", "serial_only", "threads_for", "threads_from", "use_threads"]

MIN_ITEMS = 30_000
"""Fewest points (neighbour search) or moving robots (self-spreading step) for which a kernel runs on several threads.

Measured on the project's 2-core machine, the full self-spreading step of ``amronet bench`` with threads against
one thread, stepping alternately in one process: 0.95x at 20 000 robots, 0.94-1.29x at 30 000, 1.18-1.42x at
40 000-50 000, 1.30-1.74x at 100 000. Below that the threads' start and join and the step's extra pass cost as much
as they save (the work of a few thousand robots stays in the caches)."""

LOCK = threading.Lock()
"""Held while a threaded kernel runs (numba's ``workqueue`` pool takes one caller at a time)."""

_serial = False


def configure() -> None:
    """Ask numba for a fork-safe thread pool, unless the user set ``NUMBA_THREADING_LAYER`` (see the module)."""
    if "NUMBA_THREADING_LAYER" not in os.environ:
        numba.config.THREADING_LAYER = "forksafe"


def serial_only() -> None:
    """Never use threads in this process (a sweep's workers: the pool already uses every core)."""
    global _serial
    _serial = True


def use_threads(items: int) -> bool:
    """Whether a kernel over ``items`` points or robots should run on several threads (see the module)."""
    return items >= MIN_ITEMS and not _serial and numba.config.NUMBA_NUM_THREADS > 1


def threads_for(items: int) -> int:
    """How many threads a kernel over ``items`` points or robots runs on (1 unless :func:`use_threads`)."""
    return numba.get_num_threads() if use_threads(items) else 1


@contextlib.contextmanager
def threads_from(items: int) -> Iterator[None]:
    """Within the block, kernels over ``items`` points or robots or more run threaded.

    ``amronet compile`` compiles the threaded kernels on a small run with ``threads_from(0)``.
    """
    global MIN_ITEMS
    before = MIN_ITEMS
    MIN_ITEMS = items
    try:
        yield
    finally:
        MIN_ITEMS = before
