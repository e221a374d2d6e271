"""The radio's tables in an agent-assisted quiet stretch: what the radio medium's update builds, step after step.

A quiet stretch (:mod:`.stretch_kernels`) builds each step's neighbour table itself, as
:meth:`amronet.engine.radio.RadioMedium.update` builds it, with the same compiled functions on the same numbers:

* the pairs within the radio's reach (:func:`~amronet.engine.neighbours.search_kernel`): the *geometric* table, which
  the rings and the collision checks read;
* under the built-in path-loss law with walls or shadowing
  (:attr:`~amronet.engine.radio.RadioMedium.stretch_inputs`), the margin of every pair
  (:func:`~amronet.engine.links.path_loss_candidate_margins`, taking the previous step's margin of a pair whose two
  ends have not moved) and, as the table of links, the pairs whose margin is ``>= 0``
  (:func:`~amronet.engine.links.keep_entries`); otherwise every pair is a link;
* where the drop rule reads them (``link-quality``), the margins of the links: the path-loss law's, or by distance
  (:func:`~amronet.engine.links.distance_margins`, what :attr:`~amronet.engine.table.NeighbourTable.margin` gives).

Once nodes have failed (:attr:`Radio.silent`), their pairs are dropped from the links as the radio drops them
(:meth:`~amronet.engine.radio.RadioMedium.update`'s ``silent``): a link is a pair whose margin is ``>= 0`` and whose
two ends send; the geometric table keeps every pair (their bodies stay where they are).
The links are what the agents' tracking, their connection books, the drop rules and the repair read.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.hearing import named_inputs
from amronet.engine.links import distance_margins, keep_entries, path_loss_candidate_margins
from amronet.engine.neighbours import search_kernel

__all__ = ["NO_MARGIN", "Radio", "next_radio"]

NO_MARGIN = np.zeros(0)
"""The margins of a table whose margins nobody reads (a stand-in of their type)."""


class Radio(NamedTuple):
    """The radio's search radius ``r``, its inputs and this step's tables (every sensing and driving reach is in ``r``).

    Under the unit disk (and the path-loss law without walls and shadowing) the links are the geometric table.
    """

    r: float
    indptr: np.ndarray
    """The links' rows."""
    indices: np.ndarray
    dist: np.ndarray
    margin: np.ndarray
    """The links' margins where the drop rule reads them (else :data:`NO_MARGIN`)."""
    near_indptr: np.ndarray
    """The geometric table's rows: every pair within ``r``."""
    near_indices: np.ndarray
    near_dist: np.ndarray
    near_xy: np.ndarray
    """The positions the geometric table was built of."""
    near_margin: np.ndarray
    """Its pairs' margins under the path-loss law (else :data:`NO_MARGIN`)."""
    hearing: tuple
    """The radio's :class:`~amronet.engine.hearing.HearingInputs` as a plain tuple
    (:attr:`~amronet.engine.radio.RadioMedium.stretch_inputs`): with ``wall_db`` and ``clip`` 0, every pair is a
    link."""
    silent: np.ndarray
    """Which robots send nothing ``(N,)`` (failed ones; no entries: none), a link of which is none."""


@njit(cache=True)
def next_radio(xy, radio, group, margins):  # pragma: no cover - numba
    """The radio after the robots moved to ``xy``: ``(ok, radio)`` (``ok`` false: a non-finite position, no table).

    ``radio``: a :class:`Radio` (a plain tuple); ``group``: zeros, one per robot; ``margins``: whether the links'
    margins are read (see the module docstring).
    """
    (r, _, _, _, last_margin, last_near_indptr, last_near_indices, _, last_near_xy, last_near_margin, hearing,
     silent) = radio
    h = named_inputs(hearing)
    here = xy.copy()
    ok, near_indptr, near_indices, near_dist = search_kernel(here, r, group, np.int64(1))
    if not ok:
        return False, radio
    laws = h.wall_db != 0.0 or h.clip != 0.0
    if not laws and not silent.shape[0]:  # every pair is a link, its margin that of its length
        margin = distance_margins(near_dist, h.r_c, h.n10) if margins else last_margin
        return True, (r, near_indptr, near_indices, near_dist, margin, near_indptr, near_indices, near_dist, here,
                      last_near_margin, hearing, silent)
    # (the pairs of the last table whose two ends stand still keep their margins: the same numbers)
    near_margin = path_loss_candidate_margins(here, near_indptr, near_indices, near_dist, last_near_xy,
                                              last_near_indptr, last_near_indices, last_near_margin,
                                              hearing) if laws else last_near_margin
    keep = near_margin >= 0.0 if laws else np.ones(near_dist.shape[0], np.bool_)
    if silent.shape[0]:  # (as RadioMedium._links: neither end silent)
        for i in range(near_indptr.shape[0] - 1):
            for e in range(near_indptr[i], near_indptr[i + 1]):
                if silent[i] or silent[near_indices[e]]:
                    keep[e] = False
    if keep.all():  # every pair is a link (the stand-ins passed on: a global array would be read-only, of another type)
        margin = near_margin if laws else (distance_margins(near_dist, h.r_c, h.n10) if margins else last_margin)
        return True, (r, near_indptr, near_indices, near_dist, margin, near_indptr, near_indices, near_dist, here,
                      near_margin, hearing, silent)
    indptr, indices, dist, margin = keep_entries(near_indptr, near_indices, near_dist,
                                                 near_margin if laws else near_dist, keep)
    if not laws:  # the links' margins by their lengths
        margin = distance_margins(dist, h.r_c, h.n10) if margins else last_margin
    return True, (r, indptr, indices, dist, margin, near_indptr, near_indices, near_dist, here, near_margin, hearing,
                  silent)
