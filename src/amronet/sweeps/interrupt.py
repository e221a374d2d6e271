"""A sweep stopped by Ctrl-C: what the store holds of it, in one line.

:func:`~amronet.sweeps.engine.execute_into_store` turns the ``KeyboardInterrupt`` into :class:`SweepInterrupted`
(still a ``KeyboardInterrupt``) once its workers are stopped: the counts come from the store itself, so a run
counts as stored only if its transaction committed.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Collection, Mapping
from pathlib import Path

from amronet.sweeps.store import ResultStore, RunKey, RunVersion, StoreError

__all__ = ["SweepInterrupted", "interrupted"]


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a sweep (or a figure's runs); the message says what the store holds of it.

    Attributes:
        total: Runs of the sweep.
        stored: Runs of it in the store, finished (done or failed) now or before.
        discarded: Runs that were being computed and were dropped.
        not_started: Runs not started.
        store: The store's path.
    """

    def __init__(self, total: int, stored: int, discarded: int, not_started: int, store: str | Path) -> None:
        self.total, self.stored, self.discarded, self.not_started = total, stored, discarded, not_started
        self.store = str(store)
        super().__init__(f"interrupted: {stored} of {total} runs finished and stored in {self.store}, {discarded} "
                         f"in progress discarded, {not_started} not started; run the same command again to resume")

    def __reduce__(self) -> tuple[type, tuple[int, int, int, int, str]]:
        return type(self), (self.total, self.stored, self.discarded, self.not_started, self.store)


def interrupted(store: ResultStore, total: int, pending: Collection[RunKey], seen: Mapping[RunKey, RunVersion | None],
                in_flight: Collection[RunKey], recorded: Collection[RunKey]) -> SweepInterrupted:
    """The :class:`SweepInterrupted` of a sweep of ``total`` runs whose runs ``pending`` were to run now.

    Args:
        store: The open store.
        total: Runs of the sweep.
        pending: The runs this invocation was to compute (the others were in the store already).
        seen: Their stored versions before (see :meth:`~amronet.sweeps.store.ResultStore.claim`).
        in_flight: Runs being computed when the sweep stopped.
        recorded: Runs this invocation recorded (used if the store cannot be read now).
    """
    try:
        versions = store.versions()
        stored = {key for key in pending if versions.get(key) not in (None, seen.get(key))}
    except (sqlite3.Error, StoreError):
        stored = set(recorded)
    discarded = len(set(in_flight) - stored)
    not_started = len(pending) - len(stored) - discarded
    return SweepInterrupted(total, total - discarded - not_started, discarded, not_started, store.path)
