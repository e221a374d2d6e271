"""The kernels of self-spreading and potential-field stretches: the steps between two records in one compiled call.

A step of a self-spreading or potential-field loop with a compiled step (:mod:`amronet.algorithms.self_spreading.fast`)
is two or
three kernels with Python in between: the compiled sense-decide-move, the radio's neighbour search, the books (did a
run settle?). :func:`spreading_stretch` and :func:`field_stretch` take up to ``limit`` such steps in a row, each with
the same kernels in the same order on the same numbers, and stop after the first step in which some active run's
settled state changed (the loop's books then see it, as after any step), or, for self-spreading under the ``global``
triangle rule, *before* a step in which a triangular deployment may start (the controller's Python decides those;
that step is left whole; the ``none`` and ``local`` rules' are decided in the stretch,
:mod:`amronet.algorithms.self_spreading.triangle_kernels`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.kernel_data import Csr
from amronet.engine.neighbours import search_kernel
from amronet.engine.skin_table import skin_search

__all__ = ["BAD_DRAW", "CANDIDATES", "NON_FINITE", "QUIET", "SETTLING", "Books", "Radio", "after_step",
           "after_step_skin", "settling_changed"]

QUIET = 0
"""Every step asked for was done."""
SETTLING = 1
"""The last step done changed whether an active run is settled."""
CANDIDATES = 2
"""The step after the last one done may start a triangular deployment the kernel does not decide (self-spreading's
``global`` rule): nothing of it was done."""
NON_FINITE = 3
"""A robot's position became non-finite in the last step done (its radio table was not built)."""
BAD_DRAW = 4
"""The walkers were not listed in order (cannot happen: :func:`~amronet.algorithms.common.step_kernels.list_movers`
lists them so);
the step after the last one done is left half done."""


class Radio(NamedTuple):
    """The radio's neighbour search in a stretch (:func:`~amronet.engine.neighbours.search_kernel`)."""

    reach: float
    """Every pair within ``reach`` is linked (the unit disk)."""
    group_ids: np.ndarray
    """``int64 (N,)``: each robot's group (run); robots of different groups are never linked."""
    n_groups: int
    """How many groups."""


class Books(NamedTuple):
    """What a stretch watches of the runs' books: whether an active run's settled state changes."""

    lookup: np.ndarray
    """``bool (n_states,)``: the states in which an eligible robot keeps its run unsettled."""
    eligible: np.ndarray
    """``bool (N,)``: the robots whose state counts."""
    groups: np.ndarray
    """``int64 (N,)``: each robot's run."""
    active: np.ndarray
    """``bool (n_runs,)``: the runs still running."""
    settled: np.ndarray
    """``bool (n_runs,)``: whether each run is settled now."""
    counts: np.ndarray
    """``int64 (n_runs,)``: scratch, per run."""


@njit(cache=True)
def settling_changed(state, books):  # pragma: no cover - numba
    """Whether an active run's settled state (none of its eligible robots in a ``lookup`` state) is not ``settled``."""
    lookup, eligible, groups, active, settled, counts = books
    counts[:] = 0
    for i in range(state.shape[0]):
        if eligible[i] and lookup[state[i]]:
            counts[groups[i]] += 1
    for g in range(active.shape[0]):
        if active[g] and (counts[g] == 0) != settled[g]:
            return True
    return False


@njit(cache=True, inline="always")
def after_step(xy, state, radio, books):  # pragma: no cover - numba
    """The radio's next table and the books after a step: ``(how, table)``, the table a :class:`Csr`.

    ``how``: :data:`NON_FINITE` (no table), :data:`SETTLING` (an active run's settled state changed: the stretch ends
    there) or :data:`QUIET`.
    """
    ok, indptr, indices, dist = search_kernel(xy, radio.reach, radio.group_ids, radio.n_groups)
    if not ok:
        return NON_FINITE, Csr(indptr, indices, dist)
    if settling_changed(state, books):
        return SETTLING, Csr(indptr, indices, dist)
    return QUIET, Csr(indptr, indices, dist)


@njit(cache=True, inline="always")
def after_step_skin(xy, state, radio, books, skin, reuse):  # pragma: no cover - numba
    """:func:`after_step` with the radio's table kept through a skin: ``(how, table, skin)``, the same table.

    ``skin`` and ``reuse``: as :func:`~amronet.engine.skin_table.skin_search` takes them.
    """
    ok, indptr, indices, dist, skin = skin_search(xy, radio.reach, radio.group_ids, radio.n_groups, skin, reuse)
    if not ok:
        return NON_FINITE, Csr(indptr, indices, dist), skin
    if settling_changed(state, books):
        return SETTLING, Csr(indptr, indices, dist), skin
    return QUIET, Csr(indptr, indices, dist), skin
