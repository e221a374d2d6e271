"""The same integer program solved by OR-Tools CP-SAT, an optional solver (``pip install 'amronet[optimum]'``).

The model is :mod:`~amronet.optimum.model`'s, written for CP-SAT: a Boolean ``y_j`` per kept site, a clause per
coverage row, a clause per site not linked to a base station (a chosen one has a chosen neighbour), a clause per
hop layer some row must cross, the chain inequality, and the single-commodity flow with integer flows: every chosen
site consumes one unit, ``in_v - out_v = y_v``, and only chosen sites take any, ``in_v <= U y_v`` with ``U`` the
known placement's count. The known placement is handed in whole (sites and a flow along its breadth-first tree
from the base stations) as CP-SAT's hint, and ``sum y <= U`` keeps it feasible.

Why CP-SAT: on covering problems whose LP relaxation is weak — the unit disk's, where half-weights on twice as many
sites cover every row and carry every flow — its core-based search (one worker lowers the objective's bound by
finding unsatisfiable cores of the clauses, not by the LP) proves higher bounds than HiGHS's branch and bound in the
same time; docs/optimum.md has the measured numbers. On a 2-core machine the two workers are that core
search and the LP-based search (:data:`FEW_CORE_SUBSOLVERS`); with more cores CP-SAT's own portfolio runs.

L. Perron, F. Didier, CP-SAT, Google OR-Tools (https://developers.google.com/optimization), 2023.
"""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import scipy.sparse as sp

from amronet.errors import AmronetError
from amronet.optimum.model import MipResult, hop_layers, row_need

__all__ = ["FEW_CORE_SUBSOLVERS", "available", "solve_cpsat", "tree_flow"]

FEW_CORE_SUBSOLVERS = ("core", "default_lp")
"""CP-SAT's workers on a machine of at most 2 cores: the core-based bound search and the LP-based search."""


def available() -> bool:
    """Whether OR-Tools (CP-SAT) is installed."""
    try:
        import ortools.sat.python.cp_model  # noqa: F401
    except ImportError:
        return False
    return True


def require() -> None:
    """Refuse the CP-SAT solver when OR-Tools is not installed (one line naming ``--solver`` and the fix)."""
    if not available():
        raise AmronetError("--solver: cp-sat needs OR-Tools; install it with pip install 'amronet[optimum]' "
                           "(or pip install ortools), or use --solver highs")


def tree_flow(links: sp.csr_matrix, base: np.ndarray, chosen: np.ndarray) -> dict[tuple[int, int], int]:
    """A flow for a connected placement: along its breadth-first tree from the bases, each arc carries its subtree.

    Returns:
        ``{(tail, head): units}`` with tail ``-1`` for the arcs from the base stations; every chosen site
        consumes one unit. Sites not reached are left out (the placement is assumed connected).
    """
    parent = {int(j): -1 for j in np.flatnonzero(chosen & base)}
    order = list(parent)
    head = 0
    while head < len(order):
        u = order[head]
        head += 1
        for v in links.indices[links.indptr[u]:links.indptr[u + 1]].tolist():
            if chosen[v] and v not in parent:
                parent[v] = u
                order.append(v)
    load = dict.fromkeys(order, 1)
    for v in reversed(order):
        if parent[v] >= 0:
            load[parent[v]] += load[v]
    return {(parent[v], v): load[v] for v in order}


def solve_cpsat(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray, time_limit: float, *,
                start: np.ndarray, chain: tuple[np.ndarray, int] | None = None, workers: int | None = None,
                seed: int = 0) -> MipResult:
    """Solve the model of the module docstring with CP-SAT within ``time_limit`` seconds.

    Args:
        rows: CSR ``(m, k)``: the coverage rows over the kept sites.
        links: Symmetric CSR ``(k, k)``.
        base: ``(k,)``: linked to a base station.
        time_limit: Seconds at most.
        start: A covering, connected placement (mask over the sites): the hint, and ``sum y <= start.sum()``.
        chain: The chain inequality ``(g, cells)`` (:mod:`amronet.optimum.bounds`).
        workers: CP-SAT's workers (default: the machine's cores, at least 2, at most 8).
        seed: CP-SAT's random seed.

    Returns:
        The best placement CP-SAT found (``None`` when it is ``start`` itself, as :func:`~amronet.optimum.model.solve`
        reports the incumbent), and the bound it proved.
    """
    from ortools.sat.python import cp_model

    k = rows.shape[1]
    cap = int(start.sum())
    m = cp_model.CpModel()
    y = [m.new_bool_var(f"y{j}") for j in range(k)]
    for i in range(rows.shape[0]):
        m.add_bool_or([y[j] for j in rows.indices[rows.indptr[i]:rows.indptr[i + 1]].tolist()])
    for j in np.flatnonzero(~base).tolist():
        m.add_bool_or([y[u] for u in links.indices[links.indptr[j]:links.indptr[j + 1]].tolist()] + [~y[j]])
    hops = hop_layers(links, base)
    need = int(row_need(rows, hops).max()) if rows.shape[0] else 0
    for h in range(1, need):
        m.add_bool_or([y[j] for j in np.flatnonzero(hops == h).tolist()])
    if chain is not None:
        gains, cells = chain
        m.add(sum(int(round(g)) * y[j] for j, g in enumerate(gains.tolist()) if g > 0) >= int(cells))
    flow = tree_flow(links, base, start)
    inflow: list[list] = [[] for _ in range(k)]
    outflow: list[list] = [[] for _ in range(k)]
    for u, v in zip(*sp.triu(links, 1).nonzero(), strict=True):
        for a, b in ((int(u), int(v)), (int(v), int(u))):
            f = m.new_int_var(0, cap, "")
            m.add_hint(f, flow.get((a, b), 0))
            outflow[a].append(f)
            inflow[b].append(f)
    for j in np.flatnonzero(base).tolist():
        f = m.new_int_var(0, cap, "")
        m.add_hint(f, flow.get((-1, j), 0))
        inflow[j].append(f)
    for j in range(k):
        m.add(sum(inflow[j]) - sum(outflow[j]) == y[j])
        m.add(sum(inflow[j]) <= cap * y[j])
        m.add_hint(y[j], bool(start[j]))
    m.add(sum(y) <= cap)
    m.minimize(sum(y))
    solver = cp_model.CpSolver()
    p = solver.parameters
    p.max_time_in_seconds = float(max(time_limit, 0.01))
    p.num_workers = int(workers or min(8, max(2, os.cpu_count() or 2)))
    p.random_seed = int(seed)
    if p.num_workers <= len(FEW_CORE_SUBSOLVERS):
        p.subsolvers.extend(FEW_CORE_SUBSOLVERS)
    p.catch_sigint_signal = False  # its handler outlived the search: a later Ctrl-C killed Python outright
    t0 = time.perf_counter()
    status = _solve_interruptibly(solver, m)
    seconds = time.perf_counter() - t0
    nodes = int(solver.num_branches)
    if status == cp_model.INFEASIBLE:  # the start is feasible: only a start that is not gets here (proves nothing)
        return MipResult(None, None, 0.0, "error: CP-SAT refused the start placement", seconds, nodes)
    if status not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        bound = float(solver.best_objective_bound) if status == cp_model.UNKNOWN else 0.0
        return MipResult(None, None, max(bound, 0.0), "time-limit", seconds, nodes)
    chosen = np.array([solver.boolean_value(v) for v in y], dtype=bool)
    name = "optimal" if status == cp_model.OPTIMAL else "time-limit"
    bound = float(solver.best_objective_bound)
    if name == "optimal":
        bound = max(bound, float(chosen.sum()))
    if chosen.sum() >= cap:
        return MipResult(None, None, bound, name, seconds, nodes)
    return MipResult(chosen, int(chosen.sum()), bound, name, seconds, nodes)


def _solve_interruptibly(solver, model):
    """``solver.solve(model)`` in a thread, so that Ctrl-C stops the search at once and raises here.

    CP-SAT releases the GIL while it searches; the main thread waits in short joins, where Python's own SIGINT handler
    raises ``KeyboardInterrupt``: the search is stopped, its thread joined, and the interruption goes on up.
    """
    answer: list = []
    worker = threading.Thread(target=lambda: answer.append(solver.solve(model)), name="cp-sat", daemon=True)
    worker.start()
    try:
        while worker.is_alive():
            worker.join(0.1)
    except KeyboardInterrupt:
        solver.stop_search()
        worker.join()
        raise
    return answer[0]
