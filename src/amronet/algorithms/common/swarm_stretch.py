"""Stretches of a swarm of routers: the steps between two records in one compiled call (self-spreading, the field).

With a few dozen robots per run, a step of a self-spreading or potential-field batch is mostly Python between its
kernels: the fast step's glue, the radio medium's table, the loop's books. A stretch hands the steps up to the next
recorded one to one kernel of the algorithm's
(:func:`~amronet.algorithms.self_spreading.kernels.spreading_stretch`,
:func:`~amronet.algorithms.potential_field.kernels.field_stretch`), which takes them one after another with the same
kernels on the same numbers (the walkers' draws too, through :mod:`amronet.engine.bitgen`), the radio's search
included, so every run's result is the same bit for bit (``tests/test_swarm_stretch.py``). :class:`SwarmStretch`
is what such stretches share: when one may start, the radio's search and the books' settled watch, and the
:class:`~amronet.algorithms.stepping.Stretched` the loop gets back.

A stretch runs only where its steps need nothing else: a radio that keeps every pair within its reach (the unit
disk), rings and moves that reach no farther than the table, one thread. It stops after a step that changed whether an
active run is settled, and (self-spreading under the ``global`` triangle rule) before a step in which a triangular
deployment may start.

Once nodes have failed, the loop offers a stretch only to a fast step that
:attr:`~amronet.algorithms.stepping.FastStep.silences` them, and the table it starts from has lost their links (its
geometric view has every pair). The stretch starts from that geometric view, as its own searches find every pair
within reach, failed nodes' too: its kernels must let no link of a failed node change anything (self-spreading's
read links only through state lookups that exclude ``failed``; the potential field's forces count every neighbour,
so it takes no stretch then).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from amronet.algorithms.common.swarm_stretch_kernels import BAD_DRAW, CANDIDATES, NON_FINITE, SETTLING, Books, Radio
from amronet.algorithms.stepping import StepContext, Stretched, Surroundings, Watch
from amronet.engine.kernel_data import Csr
from amronet.engine.neighbours import GroupIds
from amronet.engine.table import NeighbourTable
from amronet.threads import use_threads

__all__ = ["SwarmStretch"]

Kernel = Callable[[int, Csr, Radio, Books], tuple[int, int, Csr]]
"""An algorithm's stretch kernel, given ``(limit, table, radio, books)``: ``(done, how, table)``."""


class SwarmStretch:
    """What the stretches of a swarm of routers share (see the module docstring).

    Args:
        context: The loop's step context; :meth:`applies` must hold.
        settling: The controller's settling rule ``(lookup, eligible)``: a run is settled when none of its eligible
            robots is in a ``lookup`` state (fixed for the loop: robots are never added).
        around: The fast step's surroundings (its rings' and moves' reaches).
    """

    def __init__(self, context: StepContext, settling: tuple[np.ndarray, np.ndarray], around: Surroundings) -> None:
        ids = GroupIds.of(context.groups, len(context.swarm))
        self.radio = Radio(float(context.radio_reach), ids.ids, int(ids.count))
        self.groups = ids.ids
        self.n_runs = int(ids.count)
        self.n = len(context.swarm)
        self.settling = settling
        self.around = around
        self.counts = np.zeros(self.n_runs, dtype=np.int64)
        self.steps = 0
        """Steps taken in stretches."""
        self.silent_steps = 0
        """Steps taken in stretches once nodes had failed (:attr:`~amronet.algorithms.stepping.Watch.silent`)."""
        self.ends = {"quiet": 0, "settling": 0, "candidates": 0}
        """How many stretches ended each way: all steps taken, a run's settled state changed, a triangle may start."""

    @staticmethod
    def applies(context: StepContext) -> bool:
        """Whether steps can be taken in stretches: a radio that keeps every pair within its reach, one thread."""
        return context.keeps_every_pair and not use_threads(len(context.swarm))

    def take(self, limit: int, table: NeighbourTable, watch: Watch, kernel: Kernel) -> Stretched | None:
        """Up to ``limit`` steps through ``kernel`` from ``table``; ``None`` where no stretch can start.

        Raises:
            AssertionError: The walkers were not listed in order (cannot happen).
        """
        a = self.around
        beyond = a.sense_reach > table.r or (a.collisions and a.drive_reach > table.r)
        if (table.candidates is not None and watch.silent is None) or self.n < 2 or beyond:
            return None
        table = table.geometric  # every pair within reach: what the stretch's own searches give
        on = np.zeros(self.n_runs, dtype=np.bool_)
        on[watch.active] = True
        books = Books(*self.settling, self.groups, on, np.asarray(watch.settled, dtype=np.bool_), self.counts)
        done, how, csr = kernel(limit, Csr(table.indptr, table.indices, table.dist), self.radio, books)
        self.steps += done
        if watch.silent is not None:
            self.silent_steps += done
        if how == BAD_DRAW:
            raise AssertionError("the walkers were not listed in order")
        if how != NON_FINITE:
            self.ends[{SETTLING: "settling", CANDIDATES: "candidates"}.get(how, "quiet")] += 1
        return Stretched(done, (csr.indptr, csr.indices, csr.dist) if done else None, non_finite=how == NON_FINITE)
