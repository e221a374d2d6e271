"""Claims in the result store: which process is computing which run right now.

The ``claims`` table holds per run key the ``owner`` (a random token per sweep invocation), its ``host`` and
``pid``, ``claimed_at`` and a ``heartbeat`` (Unix time, refreshed every :data:`CLAIM_HEARTBEAT_S` s). A claim is
taken with ``BEGIN IMMEDIATE`` (:meth:`StoreClaims.claim`) and dropped in the transaction that records its run, or
when its owner stops. So two sweeps on one store never compute a run twice: the second leaves a run claimed by a
live owner to it, and takes over a *stale* claim — its owner's process is gone (same host) or its heartbeat is
older than :data:`CLAIM_LEASE_S` s (any host).
"""

from __future__ import annotations

import os
import socket
import sqlite3
import threading
import time
import uuid
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from amronet.sweeps.store_schema import CLAIMS_TABLE, RunKey, RunVersion, StoreFile, utc_now
from amronet.sweeps.worker import pid_alive

__all__ = ["CLAIM_HEARTBEAT_S", "CLAIM_LEASE_S", "ClaimOwner", "Claims", "StoreClaims"]

CLAIM_LEASE_S = 60.0
"""A claim whose heartbeat is older than this is stale: another process may take its run over."""
CLAIM_HEARTBEAT_S = 5.0
"""How often a sweep refreshes the heartbeat of its claims."""


@dataclass(frozen=True)
class ClaimOwner:
    """Who holds claims: one sweep invocation (a random token), on a host, in a process."""

    token: str
    host: str
    pid: int

    @classmethod
    def new(cls) -> ClaimOwner:
        """A fresh owner for this process."""
        return cls(uuid.uuid4().hex, socket.gethostname(), os.getpid())


@dataclass
class Claims:
    """What :meth:`StoreClaims.claim` found for the runs asked about.

    Attributes:
        claimed: Runs claimed now by the caller: compute them.
        finished: Runs recorded by another process since the caller looked (``status`` by key): do not compute.
        held: Runs claimed by another live owner (``"pid P on HOST"`` by key): wait for them.
    """

    claimed: list[RunKey] = field(default_factory=list)
    finished: dict[RunKey, str] = field(default_factory=dict)
    held: dict[RunKey, str] = field(default_factory=dict)


class StoreClaims(StoreFile):
    """The claims of a result store (see the module docstring)."""

    def versions(self) -> dict[RunKey, RunVersion]:
        """``(scenario_hash, seed) -> (status, finished_at, wall_time_s)`` of every stored run."""
        return {(h, s): (st, f, w) for h, s, st, f, w in self.conn.execute(
            "SELECT scenario_hash, seed, status, finished_at, wall_time_s FROM runs")}

    def claim(self, keys: Iterable[RunKey], owner: ClaimOwner, seen: dict[RunKey, RunVersion | None],
              lease: float = CLAIM_LEASE_S) -> Claims:
        """Claim the runs ``keys`` for ``owner``, in one ``BEGIN IMMEDIATE`` transaction.

        A run is claimed when it is still as the caller saw it (``seen``: missing, or the failed recording it
        means to retry) and nobody else holds a live claim on it (none, the caller's own, or a stale one: its
        owner's process is gone on this host, or its heartbeat is older than ``lease`` seconds).

        Returns:
            :class:`Claims`: claimed now, finished by another process meanwhile, held by another live owner.
        """
        out = Claims()
        now = time.time()
        alive: dict[tuple[str, int], bool] = {}

        def stale(host: str, pid: int, heartbeat: float) -> bool:
            if now - heartbeat > lease:
                return True
            if host != owner.host:
                return False
            if (host, pid) not in alive:
                alive[(host, pid)] = pid_alive(pid)
            return not alive[(host, pid)]

        with self._transaction() as c:
            if not self._claims_table:
                c.execute(CLAIMS_TABLE)
                self._claims_table = True
            versions = self.versions()
            holders = {(h, s): (o, host, pid, hb) for h, s, o, host, pid, hb in c.execute(
                "SELECT scenario_hash, seed, owner, host, pid, heartbeat FROM claims")}
            rows = []
            for key in keys:
                key = (key[0], int(key[1]))
                version = versions.get(key)
                if version is not None and (version[0] == "done" or version != seen.get(key)):
                    out.finished[key] = version[0]
                    continue
                holder = holders.get(key)
                if holder is not None and holder[0] != owner.token and not stale(*holder[1:]):
                    out.held[key] = f"pid {holder[2]} on {holder[1]}"
                    continue
                out.claimed.append(key)
                rows.append((*key, owner.token, owner.host, owner.pid, utc_now(), now))
            c.executemany("INSERT OR REPLACE INTO claims VALUES (?, ?, ?, ?, ?, ?, ?)", rows)
        return out

    def release(self, owner: ClaimOwner) -> None:
        """Drop every claim of ``owner`` (its runs not recorded yet become free for others)."""
        if self._claims_table:
            with self._transaction() as c:
                c.execute("DELETE FROM claims WHERE owner = ?", (owner.token,))

    @contextmanager
    def heartbeat(self, owner: ClaimOwner, interval: float = CLAIM_HEARTBEAT_S) -> Iterator[None]:
        """Refresh the heartbeat of ``owner``'s claims every ``interval`` seconds while the block runs.

        A thread with its own connection does it, so that other processes see the claims live however long a run
        takes.
        """
        stop = threading.Event()

        def beat() -> None:
            conn = sqlite3.connect(self.path, isolation_level=None, timeout=interval)
            try:
                while not stop.wait(interval):
                    try:
                        conn.execute("UPDATE claims SET heartbeat = ? WHERE owner = ?", (time.time(), owner.token))
                    except sqlite3.Error:
                        continue  # busy for a whole interval: the next beat
            finally:
                conn.close()

        thread = threading.Thread(target=beat, name="amronet-claims-heartbeat", daemon=True)
        thread.start()
        try:
            yield
        finally:
            stop.set()
            thread.join(timeout=2 * interval)
