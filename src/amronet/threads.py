"""When amronet's kernels use more than one core: large runs only, on a thread pool that survives ``fork``.

A step of a few thousand robots takes a millisecond or two, less than handing work to other threads is worth,
and a sweep already keeps every core busy with one run per worker process. A run of tens of thousands of robots
is different: its neighbour search and its sensor rings take tens of milliseconds, spent row by row and robot by
robot on independent data. Those two kernels have a threaded twin (``prange`` over rows or robots) that gives
the same numbers bit for bit; a caller picks it with :func:`use_threads`, which says yes only when

* the call handles at least :data:`MIN_ITEMS` points or robots,
* this process may use threads (:func:`serial_only` was not called: a sweep's worker processes call it, the
  pool already runs one run per core), and
* numba has more than one thread (``NUMBA_NUM_THREADS``, by default the number of cores).

numba's thread pool comes in three kinds. The GNU OpenMP one that numba picks first on Linux is not safe to
``fork`` (a child process that forks after its parent used it hangs), and amronet's sweeps fork their workers, so
:func:`configure` asks numba for a fork-safe pool (``forksafe``: Intel TBB where it is installed, else numba's
own ``workqueue``), unless the user chose one with ``NUMBA_THREADING_LAYER``. ``workqueue`` must not be entered
by two Python threads at once; callers hold :data:`LOCK` while a threaded kernel runs.
"""

from __future__ import annotations

import os
import threading

import numba

__all__ = ["LOCK", "MIN_ITEMS", "configure", "serial_only", "threads_for", "use_threads"]

MIN_ITEMS = 20_000
"""Fewest points (neighbour search) or moving robots (sensor rings) for which a kernel runs on several threads.

Measured on the project's 2-core machine: below ~10 000 the threads' start and join cost as much as they save."""

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
