"""The integer program: choose sites that cover every row and form a network connected to the base stations.

Variables: ``y_j`` in {0, 1} per kept site (the objective, the routers placed); a flow ``f_uv >= 0`` on every link
``u -> v`` between sites (both directions) and from the base stations (one source, the bases together) to every
site linked to one. Constraints:

* coverage: ``sum_{j in S_i} y_j >= 1`` for every (minimal) row ``S_i``;
* flow: every chosen site consumes one unit, ``in_v - out_v = y_v``, and only chosen sites carry any:
  ``in_v <= M y_v`` with ``M`` the most routers an improving placement may have (single-commodity flow, as Rebai et
  al. 2015 connect their grid model); a placement is connected exactly when such a flow exists;
* valid cuts that tighten the LP (Buchanan et al. 2015 use vertex separators in the same way): a chosen site not
  linked to a base station has a chosen neighbour, ``y_v <= sum_{u in N(v)} y_u``; and the hop *layers* — the
  sites ``h`` links from the bases over all sites — separate every site farther out from the bases, so
  ``sum_{L_h} y >= y_v`` for every site ``v`` beyond layer ``h``, and ``sum_{L_h} y >= 1`` for every layer some row
  needs to be crossed (every site of that row lies beyond it);
* the chain inequality of :mod:`amronet.optimum.bounds`;
* with an upper bound ``U`` from a known placement: ``sum y <= U - 1`` and ``M = U - 1`` (find a better one or
  prove none exists; scipy's HiGHS takes no starting solution, so the bound is given as a constraint, and an
  infeasible answer proves ``U`` optimal).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, linprog, milp

__all__ = ["MAX_LAYER_ENTRIES", "MipResult", "flow_model", "hop_layers", "lp_bound", "row_need", "set_cover", "solve"]


@dataclass(frozen=True)
class MipResult:
    """What the solver proved.

    Attributes:
        chosen: The best placement found (boolean mask over the sites), or ``None``.
        value: Its count, or ``None``.
        bound: A proven lower bound of the model's optimum (``inf`` when the model is infeasible).
        status: ``optimal``, ``time-limit``, ``infeasible`` or ``error: ...``.
        seconds: Wall time of the solver.
        nodes: Branch-and-bound nodes explored.
    """

    chosen: np.ndarray | None
    value: int | None
    bound: float
    status: str
    seconds: float
    nodes: int


MAX_LAYER_ENTRIES = 5_000_000
"""Most nonzeros the conditional hop-layer cuts may add (beyond, they are left out)."""


def hop_layers(links: sp.csr_matrix, base: np.ndarray) -> np.ndarray:
    """Fewest links from the bases to each site over all sites (1: linked to a base; 0 for no path, never used)."""
    k = len(base)
    hops = np.zeros(k, dtype=np.int64)
    frontier = base.copy()
    hops[frontier] = 1
    level = 1
    while frontier.any():
        level += 1
        nxt = (links @ frontier.astype(np.int32) > 0) & (hops == 0)
        hops[nxt] = level
        frontier = nxt
    return hops


def row_need(rows: sp.csr_matrix, hops: np.ndarray) -> np.ndarray:
    """Per row, the fewest hops of its sites: every placement holds a site at least that far out."""
    h = np.where(hops > 0, hops, np.iinfo(np.int64).max)[rows.indices]
    return np.minimum.reduceat(h, rows.indptr[:-1]) if len(h) else np.zeros(0, np.int64)


def flow_model(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray, big_m: int | None = None,
               cuts: bool = True, chain: tuple[np.ndarray, int] | None = None
               ) -> tuple[np.ndarray, list[LinearConstraint], np.ndarray, Bounds]:
    """The model of the module docstring: ``(c, constraints, integrality, bounds)`` for :func:`scipy.optimize.milp`.

    Args:
        rows: CSR ``(m, k)``: the coverage rows over the sites.
        links: Symmetric CSR ``(k, k)``.
        base: ``(k,)``: linked to a base station.
        big_m: The most routers a placement the model must admit has (``M``; default: every site).
        cuts: Add the neighbour and hop-layer cuts.
        chain: The chain inequality ``(g, cells)``: ``sum g_v y_v >= cells`` (:mod:`amronet.optimum.bounds`).
    """
    k = rows.shape[1]
    coo = sp.triu(links, 1).tocoo() if links.nnz else sp.coo_matrix((k, k))
    tail = np.concatenate([coo.row, coo.col]).astype(np.int64)
    head = np.concatenate([coo.col, coo.row]).astype(np.int64)
    src = np.flatnonzero(base)
    n_arcs = len(tail) + len(src)
    nv = k + n_arcs
    big = float(k if big_m is None else max(big_m, 1))
    arc = np.arange(n_arcs) + k
    heads = np.concatenate([head, src])
    # in_v - out_v - y_v = 0
    inflow = sp.csr_matrix((np.ones(n_arcs), (heads, arc)), shape=(k, nv))
    outflow = sp.csr_matrix((np.ones(len(tail)), (tail, arc[:len(tail)])), shape=(k, nv))
    ident = sp.csr_matrix((np.ones(k), (np.arange(k), np.arange(k))), shape=(k, nv))
    blocks = [LinearConstraint(sp.hstack([rows, sp.csr_matrix((rows.shape[0], n_arcs))]).tocsr(), 1, np.inf),
              LinearConstraint((inflow - outflow - ident).tocsr(), 0, 0),
              LinearConstraint((inflow - big * ident).tocsr(), -np.inf, 0)]
    if cuts:
        far = np.flatnonzero(~base)
        if len(far):
            own = sp.csr_matrix((np.ones(len(far)), (np.arange(len(far)), far)), shape=(len(far), k))
            nb = links[far].tocsr() - own
            blocks.append(LinearConstraint(sp.hstack([nb, sp.csr_matrix((len(far), n_arcs))]).tocsr(), 0, np.inf))
        blocks += _layer_cuts(rows, links, base, nv)
    if chain is not None:
        gains, cells = chain
        blocks.append(LinearConstraint(sp.csr_matrix(np.concatenate([gains, np.zeros(n_arcs)])[None, :]), cells,
                                       np.inf))
    c = np.concatenate([np.ones(k), np.zeros(n_arcs)])
    integrality = np.concatenate([np.ones(k), np.zeros(n_arcs)])
    bounds = Bounds(np.zeros(nv), np.concatenate([np.ones(k), np.full(n_arcs, big)]))
    return c, blocks, integrality, bounds


def _layer_cuts(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray, nv: int) -> list[LinearConstraint]:
    """``sum_{L_h} y >= y_v`` for sites beyond layer ``h``, and ``>= 1`` for layers every row beyond must cross."""
    hops = hop_layers(links, base)
    need = int(row_need(rows, hops).max()) if rows.shape[0] else 0
    top = int(hops.max())
    out = []
    if need > 1:  # layers 1 .. need - 1 each hold a chosen site
        layers = [np.flatnonzero(hops == h) for h in range(1, need)]
        r = np.concatenate([np.full(len(s), i) for i, s in enumerate(layers)])
        out.append(LinearConstraint(sp.csr_matrix((np.ones(len(r)), (r, np.concatenate(layers))),
                                                  shape=(len(layers), nv)), 1, np.inf))
    sizes = np.bincount(hops, minlength=top + 1)
    beyond = len(hops) - np.cumsum(sizes)  # sites beyond layer h
    if int((sizes[1:top] * beyond[1:top]).sum()) > MAX_LAYER_ENTRIES:
        return out  # too many conditional cuts: the unconditional ones only
    data, ri, ci, row = [], [], [], 0
    for h in range(1, top):
        layer = np.flatnonzero(hops == h)
        for v in np.flatnonzero(hops > h).tolist():
            ri.append(np.full(len(layer) + 1, row))
            ci.append(np.append(layer, v))
            data.append(np.append(np.ones(len(layer)), -1.0))
            row += 1
    if row:
        out.append(LinearConstraint(sp.csr_matrix((np.concatenate(data), (np.concatenate(ri), np.concatenate(ci))),
                                                  shape=(row, nv)), 0, np.inf))
    return out


def solve(model: tuple, k: int, time_limit: float, *, cutoff: int | None = None, fixed: np.ndarray | None = None,
          incumbent: int | None = None, node_limit: int | None = None, log: bool = False) -> MipResult:
    """Solve a model of :func:`flow_model` (or :func:`set_cover`) with HiGHS within ``time_limit`` seconds.

    Args:
        model: ``(c, constraints, integrality, bounds)``.
        k: Number of sites (the first ``k`` variables).
        time_limit: Seconds at most.
        cutoff: Look only for placements of at most this many routers (``sum y <= cutoff``).
        fixed: ``(k,)`` of -1 (free), 0 or 1: sites fixed out or in (a neighbourhood search's window).
        incumbent: The count of a placement known to exist. scipy's HiGHS takes no starting solution, and reports no
            dual bound when it stops without a solution of its own; so a binary column ``s`` of cost ``incumbent``
            is added that relaxes every constraint a placement of no routers violates: ``y = 0, s = 1`` is a
            solution of value ``incumbent`` that HiGHS finds at once. The model's optimum becomes
            ``min(optimum, incumbent)``, its dual bound stays a lower bound of the optimum where it is below
            ``incumbent``, and the solution with ``s = 1`` stands for the known placement (reported as none).
        node_limit: Branch-and-bound nodes at most.
        log: Print HiGHS's log.
    """
    c, constraints, integrality, bounds = model
    if incumbent is not None:
        c, constraints, integrality, bounds = _with_incumbent(model, float(incumbent))
    if cutoff is not None:
        constraints = [*constraints, LinearConstraint(sp.csr_matrix((np.ones(k), (np.zeros(k), np.arange(k))),
                                                                    shape=(1, len(c))), -np.inf, cutoff)]
    if fixed is not None:
        lo, hi = bounds.lb.copy(), bounds.ub.copy()
        lo[:k][fixed == 1] = 1.0
        hi[:k][fixed == 0] = 0.0
        bounds = Bounds(lo, hi)
    options = {"time_limit": float(max(time_limit, 0.01)), "mip_rel_gap": 0.0, "presolve": True, "disp": log}
    if node_limit is not None:
        options["node_limit"] = int(node_limit)
    t0 = time.perf_counter()
    res = milp(c, constraints=constraints, integrality=integrality, bounds=bounds, options=options)
    seconds = time.perf_counter() - t0
    nodes = int(getattr(res, "mip_node_count", 0) or 0)
    if res.status == 2:
        return MipResult(None, None, math.inf, "infeasible", seconds, nodes)
    if res.status not in (0, 1):
        return MipResult(None, None, 0.0, f"error: {res.message}", seconds, nodes)
    bound = getattr(res, "mip_dual_bound", None)
    bound = 0.0 if bound is None or not np.isfinite(bound) else float(bound)
    if res.x is None:
        return MipResult(None, None, bound, "time-limit", seconds, nodes)
    if incumbent is not None and res.x[-1] > 0.5:  # the known placement: nothing better was found
        status = "optimal" if res.status == 0 else "time-limit"
        bound = float(incumbent) if status == "optimal" else bound
        return MipResult(None, None, bound, status, seconds, nodes)
    chosen = res.x[:k] > 0.5
    status = "optimal" if res.status == 0 else "time-limit"
    if status == "optimal":
        bound = max(bound, float(res.fun))
    return MipResult(chosen, int(chosen.sum()), bound, status, seconds, nodes)


def _with_incumbent(model: tuple, cost: float) -> tuple:
    """The model with the column ``s`` of :func:`solve`'s ``incumbent`` (last)."""
    c, constraints, integrality, bounds = model
    out = []
    for con in constraints:
        lo = np.broadcast_to(np.asarray(con.lb, dtype=float), (con.A.shape[0],))
        col = np.where(np.isfinite(lo) & (lo > 0), lo, 0.0)
        out.append(LinearConstraint(sp.hstack([sp.csr_matrix(con.A), sp.csr_matrix(col[:, None])]).tocsr(),
                                    con.lb, con.ub))
    return (np.append(c, cost), out, np.append(integrality, 1), Bounds(np.append(bounds.lb, 0.0),
                                                                        np.append(bounds.ub, 1.0)))


def set_cover(rows: sp.csr_matrix) -> tuple:
    """Coverage alone, without connectivity: ``min sum y`` with ``rows @ y >= 1`` (a relaxation of the model)."""
    k = rows.shape[1]
    return (np.ones(k), [LinearConstraint(rows.tocsr(), 1, np.inf)], np.ones(k), Bounds(np.zeros(k), np.ones(k)))


def lp_bound(model: tuple, time_limit: float) -> float | None:
    """The LP relaxation's optimum (integrality dropped), or ``None`` when it does not finish in time."""
    c, constraints, _, bounds = model
    a = sp.vstack([con.A for con in constraints]).tocsr()
    lo = np.concatenate([np.broadcast_to(con.lb, con.A.shape[0]) for con in constraints])
    hi = np.concatenate([np.broadcast_to(con.ub, con.A.shape[0]) for con in constraints])
    eq = lo == hi
    ub_rows = sp.vstack([a[np.isfinite(hi) & ~eq], -a[np.isfinite(lo) & ~eq]]).tocsr()
    ub_vals = np.concatenate([hi[np.isfinite(hi) & ~eq], -lo[np.isfinite(lo) & ~eq]])
    res = linprog(c, A_ub=ub_rows, b_ub=ub_vals, A_eq=a[eq] if eq.any() else None, b_eq=lo[eq] if eq.any() else None,
                  bounds=list(zip(bounds.lb, bounds.ub, strict=True)), method="highs",
                  options={"time_limit": float(max(time_limit, 0.01))})
    return float(res.fun) if res.status == 0 else None
