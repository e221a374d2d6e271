"""The Dask worker plugin of a ``LocalCluster`` that amronet starts: its workers ignore Ctrl-C.

Ctrl-C in a terminal reaches every process of the sweep; a Dask worker would stop on it by itself, half-way and
with tracebacks, while the sweep stops the cluster in order (:meth:`~amronet.sweeps.dask_executor.DaskExecutor.
close`). Imported only when Dask is (``amronet[cluster]``).
"""

from __future__ import annotations

import contextlib
import signal
from typing import Any

from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["IgnoreInterrupt"]


class IgnoreInterrupt(WorkerPlugin):
    """Each worker (and each one started later) ignores ``SIGINT``."""

    name = "amronet-ignore-sigint"

    def setup(self, worker: Any) -> None:  # noqa: D102
        with contextlib.suppress(ValueError):  # not the worker process's main thread: leave it
            signal.signal(signal.SIGINT, signal.SIG_IGN)
