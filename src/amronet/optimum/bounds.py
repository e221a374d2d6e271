"""Lower bounds that need no branching: hops from the base stations, and the new cells a chain of routers can add.

**The hop bound (straight line).** Links and coverage never reach farther than the radio's reach ``R`` (``r_c`` for
the unit disk and for the multi-wall model without shadowing, whose walls only shorten links; with shadowing the
clipped field's longest link). So the ``h``-th router of a chain from a base station stands within ``h R`` of it, and
the farthest sample cell, ``D`` from the nearest base station, needs a router within ``R`` of it:
``routers >= ceil((D - R) / R)``. The distance is the straight line, not the walking distance: the unit disk links
through walls (and so covers through them), so a walking distance would overstate what is needed. This bound holds
for every placement, on the lattice or not, for the chosen coverage sample.

**The hop bound (lattice).** Over the candidate sites, the fewest links from a base station to a site that covers a
cell; the largest of these over the cells. Every site of that cell is at least that many links out, and a chain to
it holds a router per link.

**The chain inequality** (added to the integer program; it lifts the LP bound where connectivity forces overlap).
Order a connected placement by breadth-first search from the base stations: every router ``v`` has a parent
``p(v)`` before it (a chosen neighbour, or a base station). A cell is first covered by some router ``v``, and not by
``p(v)``, so the cells covered number at most ``sum_v |cov(v) minus cov(p(v))|``. With
``g_v = |cov(v)| - min_{p in N(v)} |cov(v) & cov(p)|`` (``|cov(v)|`` when ``v`` links to a base station, whose
cells are not in the sample) this gives the valid inequality ``sum_v g_v y_v >= cells``: a router whose neighbours
all overlap it by a lens adds at most a disk minus that lens.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from amronet.optimum.instance import Instance
from amronet.optimum.model import hop_layers, row_need
from amronet.optimum.reduce import Reduced, distinct_rows

__all__ = ["chain_gains", "hop_bound_lattice", "hop_bound_straight"]


def hop_bound_straight(inst: Instance) -> int:
    """``ceil((D - R) / R)``, ``D`` the farthest sample cell's straight-line distance to its nearest base station."""
    if len(inst.cells) == 0:
        return 0
    xy = inst.omap.cell_centres(*np.unravel_index(inst.cells, inst.omap.shape))
    d = np.full(len(xy), np.inf)
    for b in inst.bases_xy:
        d = np.minimum(d, np.hypot(xy[:, 0] - b[0], xy[:, 1] - b[1]))
    reach = inst.reach
    return max(0, math.ceil((float(d.max()) - reach) / reach - 1e-9))


def hop_bound_lattice(red: Reduced) -> int:
    """The largest, over the rows, of the fewest links from a base station to a site of the row."""
    if red.rows.shape[0] == 0:
        return 0
    return int(row_need(red.rows, hop_layers(red.links, red.base_linked)).max())


def chain_gains(inst: Instance, red: Reduced) -> tuple[np.ndarray, int]:
    """The chain inequality's coefficients ``g`` over the kept sites and its right-hand side (the sample's cells)."""
    groups, rows = distinct_rows(inst.cover[:, red.keep].tocsr())
    weight = np.bincount(groups, minlength=rows.shape[0]).astype(np.float64)
    cov = rows.tocsc().astype(np.float64)
    size = cov.T @ weight
    overlap = (cov.T @ sp.csr_matrix(cov.multiply(weight[:, None]))).tocsr()
    links = red.links.tocsr()
    k = red.n
    deg = np.diff(links.indptr)
    heads = np.repeat(np.arange(k), deg)
    shared = np.asarray(overlap[heads, links.indices]).ravel() if len(heads) else np.zeros(0)
    least = np.full(k, np.inf)
    has = deg > 0
    if has.any():
        least[has] = np.minimum.reduceat(shared, links.indptr[:-1][has])
    gains = np.where(red.base_linked | ~has, size, size - np.where(has, least, 0.0))
    return gains, len(inst.cells)
