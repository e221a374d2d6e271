"""The kernels of self-spreading and potential-field stretches: the steps between two records in one compiled call.

A step of a self-spreading or potential-field loop with a compiled step (:mod:`amronet.algorithms.self_spreading.fast`)
is two or
three kernels with Python in between: the compiled sense-decide-move, the radio's neighbour search, the books (did a
run settle?). :func:`spreading_stretch` and :func:`field_stretch` take up to ``limit`` such steps in a row, each with
the same kernels in the same order on the same numbers, and stop after the first step in which some active run's
settled state changed (the loop's books then see it, as after any step), or, for self-spreading, *before* a step in
which a triangular deployment may start (the controller's Python decides those; that step is left whole).
"""

from __future__ import annotations

from numba import njit

from amronet.engine.neighbours import search_kernel

__all__ = ["BAD_DRAW", "CANDIDATES", "NON_FINITE", "QUIET", "SETTLING", "after_step", "settling_changed"]

QUIET = 0
"""Every step asked for was done."""
SETTLING = 1
"""The last step done changed whether an active run is settled."""
CANDIDATES = 2
"""The step after the last one done may start a triangular deployment: nothing of it was done."""
NON_FINITE = 3
"""A robot's position became non-finite in the last step done (its radio table was not built)."""
BAD_DRAW = 4
"""The walkers were not listed in order (cannot happen: :func:`~amronet.algorithms.common.step_kernels.list_movers`
lists them so);
the step after the last one done is left half done."""


@njit(cache=True)
def settling_changed(state, lookup, eligible, groups, active, settled, counts):  # pragma: no cover - numba
    """Whether an active run's settled state (none of its eligible robots in a ``lookup`` state) is not ``settled``."""
    counts[:] = 0
    for i in range(state.shape[0]):
        if eligible[i] and lookup[state[i]]:
            counts[groups[i]] += 1
    for g in range(active.shape[0]):
        if active[g] and (counts[g] == 0) != settled[g]:
            return True
    return False


@njit(cache=True, inline="always")
def after_step(xy, state, radio, watch):  # pragma: no cover - numba
    """The radio's next table and the books after a step: ``(how, indptr, indices, dist)``.

    ``how``: :data:`NON_FINITE` (no table), :data:`SETTLING` (an active run's settled state changed: the stretch ends
    there) or :data:`QUIET`.
    """
    reach, group_ids, n_groups = radio
    lookup, eligible, groups, active, settled, counts = watch
    ok, indptr, indices, dist = search_kernel(xy, reach, group_ids, n_groups)
    if not ok:
        return NON_FINITE, indptr, indices, dist
    if settling_changed(state, lookup, eligible, groups, active, settled, counts):
        return SETTLING, indptr, indices, dist
    return QUIET, indptr, indices, dist
