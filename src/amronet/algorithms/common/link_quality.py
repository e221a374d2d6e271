"""Location-free building blocks of self-spreading: what a router can do with the link margins its radio reports.

A router's radio reports the received signal strength of every link it hears; the neighbour table carries it as the
link's margin over the usable-link threshold (:attr:`~amronet.engine.table.NeighbourTable.margin`, dB). The helpers
here read the margins of a robot's own row and per-robot state only, never a position or a distance:

* :func:`strongest_references`: reference tracking by signal (keep the current reference while it is heard, else
  take the strongest one), the best margin to any reference and the strongest reference of another status;
* :class:`MarginSmoother`: a per-robot exponential moving average of a margin, restarted when nothing is heard;
* :func:`anchor_margins`: the margins of a robot's links to two given nodes (its triangle's references);
* :class:`MarginSearch`: the run-and-tumble (chemotaxis) search of a triangle router for the point where both of its
  links have a target margin (see :mod:`amronet.algorithms.self_spreading.controller` for the rule).

Every array is per robot and every update touches only the robots passed in, so several runs can share them
(:attr:`~amronet.algorithms.base.Controller.batchable`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from amronet.algorithms.common.references import track_references
from amronet.engine.table import NeighbourTable

__all__ = ["LinkView", "MarginSearch", "MarginSmoother", "anchor_margins", "strongest_references"]


@dataclass(frozen=True)
class LinkView:
    """What each tracking robot hears of the references around it (arrays aligned with ``who``).

    Attributes:
        current: Current reference after this step's update, -1 if none is heard.
        best_margin: Best margin (dB) of a link to any reference heard, ``-inf`` if none.
        other: Strongest reference heard whose status differs from the current reference's, -1 if none.
        other_margin: Margin of the link to ``other``, ``-inf`` if none.
    """

    current: np.ndarray
    best_margin: np.ndarray
    other: np.ndarray
    other_margin: np.ndarray

    @property
    def has_reference(self) -> np.ndarray:
        """Robots that hear at least one reference."""
        return self.current >= 0


def strongest_references(
    table: NeighbourTable,
    who: np.ndarray,
    current: np.ndarray,
    is_reference: np.ndarray,
    status: np.ndarray,
    want_other: bool = True,
) -> LinkView:
    """Update the current references of the robots ``who`` by link margin instead of distance.

    The rules of :func:`~amronet.algorithms.common.references.track_references` (keep the current reference while it is
    heard, otherwise take the best one) with "best" meaning the strongest link, not the nearest node: the table's
    distances are replaced by negated margins before tracking, so no distance is read.

    Args:
        table: This step's neighbour table.
        who: Indices of the tracking robots ``(M,)``.
        current: Their current references before this step ``(M,)`` (-1: none).
        is_reference: Boolean mask over all nodes: which ones serve as references.
        status: Status of all nodes.
        want_other: Look for references of another status.

    Returns:
        The updated view; ties in margin go to the lower node id.
    """
    signal = replace(table, dist=-np.asarray(table.margin, dtype=np.float64), candidates=None)
    view = track_references(signal, who, current, is_reference, status, want_other=want_other)
    return LinkView(current=view.current, best_margin=-view.nearest_distance, other=view.other,
                    other_margin=-view.other_distance)


class MarginSmoother:
    """Per-robot exponential moving average of a link margin, restarted when the robot hears nothing.

    Args:
        n: Number of robots.
        dt: Step length, seconds.
        smoothing_s: Time constant, seconds (0: the raw margin).

    Attributes:
        alpha: Weight of a new sample, ``1 - exp(-dt / smoothing_s)``.
        value: Smoothed margin of every robot, ``nan`` for a robot with no history.
    """

    def __init__(self, n: int, dt: float, smoothing_s: float) -> None:
        self.alpha = 1.0 if smoothing_s == 0 else 1.0 - float(np.exp(-dt / smoothing_s))
        self.value = np.full(n, np.nan)

    def update(self, who: np.ndarray, margin: np.ndarray) -> np.ndarray:
        """Feed this step's margins of the robots ``who`` (``-inf``: nothing heard); return their smoothed margins.

        A robot without history starts at its sample; one that hears nothing loses its history (``nan``).
        """
        old = self.value[who]
        # no invalid operation to silence: a kept value is finite or nan (never inf), so no inf - inf arises
        new = np.where(np.isnan(old), margin, old + self.alpha * (margin - old))
        new[~np.isfinite(margin)] = np.nan
        self.value[who] = new
        return new

    def restart(self, who: np.ndarray) -> None:
        """Forget the history of the robots ``who`` (a mask or indices)."""
        self.value[who] = np.nan


@njit(cache=True)
def _anchor_margins(who, anchors, indptr, indices, margin, out):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        i = who[m]
        for k in range(anchors.shape[1]):
            a = anchors[m, k]
            out[m, k] = -np.inf
            lo = indptr[i]
            hi = indptr[i + 1]
            while lo < hi:  # rows are sorted by neighbour id
                mid = (lo + hi) // 2
                if indices[mid] < a:
                    lo = mid + 1
                else:
                    hi = mid
            if a >= 0 and lo < indptr[i + 1] and indices[lo] == a:
                out[m, k] = margin[lo]


def anchor_margins(table: NeighbourTable, who: np.ndarray, anchors: np.ndarray) -> np.ndarray:
    """Margins (dB) of the links from the robots ``who`` to their anchors ``(M, K)``; ``-inf`` where not heard."""
    who = np.asarray(who, dtype=np.int64)
    anchors = np.ascontiguousarray(anchors, dtype=np.int64).reshape(len(who), -1)
    out = np.empty(anchors.shape)
    if len(who):
        _anchor_margins(who, anchors, table.indptr, table.indices, np.asarray(table.margin, dtype=np.float64), out)
    return out


class MarginSearch:
    """Run-and-tumble search for the point where the links to two anchors both have the margin ``target_db``.

    The search minimizes ``f = (m_i - target)^2 + (m_j - target)^2`` over the robot's position, reading only the
    two margins: :meth:`step` says who keeps its heading (``f`` went down since the last step), who tumbles (a new
    random heading), who turns around (its last step lost a link) and who is done.

    Args:
        n: Number of robots.
        target_db: The margin sought on both links (dB).
        tolerance_db: Done when both margins are within this of ``target_db``.
        loss_db: Done when a margin falls below this, having been at or above it the step before.
        give_up_steps: Done after this many steps in a row without lowering ``f`` below its best so far.
        max_s: Done after searching this long (seconds).

    Attributes:
        anchors: The two anchors of every robot ``(n, 2)`` (-1: none).
        last: The margins read at the previous step ``(n, 2)`` (``nan`` before the first).
        f_last: ``f`` at the previous step (``inf`` before the first).
        f_best: The lowest ``f`` so far.
        stale: Steps in a row without a new lowest ``f``.
        started: When each robot's search started (s).
    """

    def __init__(self, n: int, target_db: float, tolerance_db: float, loss_db: float, give_up_steps: int,
                 max_s: float) -> None:
        self.target_db = float(target_db)
        self.tolerance_db = float(tolerance_db)
        self.loss_db = float(loss_db)
        self.give_up_steps = int(give_up_steps)
        self.max_s = float(max_s)
        self.anchors = np.full((n, 2), -1, dtype=np.int64)
        self.last = np.full((n, 2), np.nan)
        self.f_last = np.full(n, np.inf)
        self.f_best = np.full(n, np.inf)
        self.stale = np.zeros(n, dtype=np.int64)
        self.started = np.zeros(n)

    def start(self, who: np.ndarray, anchors: np.ndarray, t: float) -> None:
        """Start the search of robots ``who`` with anchors ``(M, 2)`` at time ``t``."""
        self.anchors[who] = anchors
        self.last[who] = np.nan
        self.f_last[who] = np.inf
        self.f_best[who] = np.inf
        self.stale[who] = 0
        self.started[who] = t

    def step(self, who: np.ndarray, margins: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One step of the search of robots ``who``, given their anchor margins ``(M, 2)`` (``-inf``: not heard).

        Returns:
            ``(tumble, reverse, done)`` masks ``(M,)``: who should turn to a fresh random heading (``f`` did not go
            down), who should turn around (its last step lost a link it heard: back the way it came), and who ends
            its search (on target, a link fell below ``loss_db``, no progress for ``give_up_steps`` steps, or out of
            time).
        """
        f = np.sum((margins - self.target_db) ** 2, axis=1)  # inf when an anchor is not heard
        on_target = np.all(np.abs(margins - self.target_db) <= self.tolerance_db, axis=1)
        last = self.last[who]
        with np.errstate(invalid="ignore"):
            fell = np.any((last >= self.loss_db) & (margins < self.loss_db), axis=1)
        reverse = np.any(np.isfinite(last) & ~np.isfinite(margins), axis=1)
        better = f < self.f_best[who]
        self.stale[who] = np.where(better, 0, self.stale[who] + 1)
        self.f_best[who] = np.where(better, f, self.f_best[who])
        tumble = ~(f < self.f_last[who]) & ~reverse
        self.f_last[who] = f
        self.last[who] = margins
        done = (on_target | fell | (self.stale[who] >= self.give_up_steps)
                | (t - self.started[who] >= self.max_s - 1e-9))
        return tumble, reverse, done
