"""The executor interface: where jobs run (:mod:`amronet.sweeps.executors` picks one).

An executor takes a picklable function and a list of picklable jobs and yields ``(index, result)`` as the jobs
finish (:meth:`Executor.imap_unordered`). An exception raised by the function is re-raised in the caller (the
sweep's worker function never raises for a failed run; see :mod:`amronet.sweeps.worker`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from typing import Any, Self

__all__ = ["Executor"]


class Executor:
    """Runs jobs somewhere and yields their results as they complete."""

    name = "executor"
    reports = False
    """Whether :meth:`imap_unordered` takes ``on_report``: called in the caller's thread with ``(index, STARTED)``
    as a job starts and ``(index, item)`` for every item its function reports (:func:`amronet.sweeps.worker.
    report`) while it runs, before the job's own ``(index, result)`` (:class:`~amronet.sweeps.executors.
    LocalExecutor` does; elsewhere the result carries everything)."""

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

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
