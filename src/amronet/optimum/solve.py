"""The search for the optimum: bounds, a quick placement, local search, then HiGHS on the whole model.

Phases, within ``time_limit`` seconds (building and reducing the instance come first and are timed apart):

1. the hop bounds; the greedy connected cover (:mod:`~amronet.optimum.heuristic`);
2. coverage alone, a set cover ILP (at most a tenth of the time), and the model's LP relaxation (likewise);
3. on a fine lattice (more than :data:`COARSE_FROM` kept sites) the lattice of twice the spacing first, which the
   fine one contains: its best placement, its removed sites replaced by their dominators, starts the fine search
   (coarse-to-fine, a quarter of the time);
4. local search over windows (:mod:`~amronet.optimum.search`, up to 30 % of the time);
5. the whole model for the rest of the time: HiGHS with ``sum y <= best - 1`` (it finds a better placement or
   proves a bound); with ``solver="cp-sat"``, OR-Tools CP-SAT first for :data:`CPSAT_SHARE` of it, the best
   placement as its hint (:mod:`~amronet.optimum.cpsat`, an optional extra), then HiGHS from CP-SAT's best, unless
   CP-SAT proved it optimal; the larger of the two bounds counts.

The lower bound is the largest of the solver's proven bound, the set cover's and the hop bounds: each is a valid
lower bound of the same lattice problem. With a time limit that is reached, what is found depends on the machine's
speed; a problem solved to the end gives the same answer everywhere.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.engine.network import connected_to
from amronet.errors import AmronetError
from amronet.optimum.bounds import chain_gains, hop_bound_lattice, hop_bound_straight
from amronet.optimum.cpsat import require as require_cpsat
from amronet.optimum.cpsat import solve_cpsat
from amronet.optimum.heuristic import connected, covers_all, greedy_connected_cover, prune
from amronet.optimum.instance import Instance, build_instance, check_feasible
from amronet.optimum.model import flow_model, lp_bound, set_cover, solve
from amronet.optimum.reduce import Reduced, reduce_instance
from amronet.optimum.report import Optimum
from amronet.optimum.search import improve
from amronet.world.occupancy import OccupancyMap

__all__ = ["COARSE_FROM", "MAX_TIME_LIMIT_S", "SOLVERS", "check_solver", "check_time_limit", "find_optimum", "verify"]

COARSE_FROM = 400
"""Kept sites from which the lattice of twice the spacing is searched first."""

MAX_TIME_LIMIT_S = 7 * 24 * 3600.0
"""The longest time limit taken (a week)."""

SOLVERS = ("highs", "cp-sat")
"""The last phase's solvers: HiGHS (``scipy.optimize.milp``), or OR-Tools CP-SAT (an optional extra) then HiGHS."""

CPSAT_SHARE = 0.5
"""With ``solver="cp-sat"``, the share of the last phase CP-SAT gets; HiGHS continues from its best for the rest."""


def _solver_name(solver: str = "highs") -> str:
    if solver == "cp-sat":
        from ortools import __version__

        return f"OR-Tools CP-SAT {__version__}, then {_solver_name()}"
    try:
        from scipy.optimize._highspy import _core

        return (f"HiGHS {_core.HIGHS_VERSION_MAJOR}.{_core.HIGHS_VERSION_MINOR}.{_core.HIGHS_VERSION_PATCH} "
                "(scipy.optimize.milp)")
    except (ImportError, AttributeError):  # pragma: no cover - another scipy layout
        return "HiGHS (scipy.optimize.milp)"


def find_optimum(map_ref: str | OccupancyMap, bases: Sequence[tuple[float, float]], r_c: float, spacing: float, *,
                 radio: dict[str, Any] | None = None, seed: int = 0, time_limit: float = 60.0,
                 coarse: bool | None = None, solver: str = "highs", log: Callable[[str], None] | None = None
                 ) -> Optimum:
    """The fewest routers that cover the reachable free space and connect to the base stations, with a proven bound.

    Args:
        map_ref: A built-in map's name, a ROS map_server YAML path, or a map.
        bases: Base-station positions ``(x, y)`` (m).
        r_c: The radio's range (m).
        spacing: The candidate lattice's spacing (m).
        radio: Radio fields beyond ``r_c`` (``model``, ``wall_db``, ``shadowing_db``); ``None``: the unit disk.
        seed: Seed of the radio's shadowing field (the field of a run with this seed).
        time_limit: Seconds for the search (heuristics and solver).
        coarse: Search the lattice of twice the spacing first (``None``: when the kept sites exceed
            :data:`COARSE_FROM`).
        solver: The last phase's solver, ``highs`` or ``cp-sat`` (needs OR-Tools: ``pip install 'amronet[optimum]'``).
        log: Called with a line per phase (progress).

    Raises:
        AmronetError: Bad input, one line naming the option.
    """
    check_time_limit(time_limit)
    check_solver(solver)
    say = log or (lambda line: None)
    t0 = time.perf_counter()
    inst = build_instance(map_ref, bases, r_c, spacing, radio=radio, seed=seed)
    t_build = time.perf_counter() - t0
    red = reduce_instance(inst)
    t_reduce = time.perf_counter() - t0 - t_build
    say(f"instance: {inst.n_sites} sites, {red.n} kept, {red.rows.shape[0]} rows ({t_build + t_reduce:.1f} s)")
    out = _search(inst, red, float(time_limit), coarse, say, solver=solver)
    out.seconds.update(build=t_build, reduce=t_reduce, total=time.perf_counter() - t0)
    return out


def check_time_limit(time_limit: float, option: str = "--time-limit") -> None:
    """Refuse a time limit that is not a number of seconds > 0 and at most :data:`MAX_TIME_LIMIT_S` (one line).

    Raises:
        AmronetError: Naming ``option``.
    """
    if not (isinstance(time_limit, int | float) and math.isfinite(time_limit) and 0 < time_limit <= MAX_TIME_LIMIT_S):
        raise AmronetError(f"{option}: must be a number of seconds > 0 and at most {MAX_TIME_LIMIT_S:g}, "
                           f"got {time_limit!r}")


def check_solver(solver: str) -> None:
    """Refuse an unknown solver, and CP-SAT when OR-Tools is not installed (one line naming ``--solver``).

    Raises:
        AmronetError: Naming ``--solver``.
    """
    if solver not in SOLVERS:
        raise AmronetError(f"--solver: unknown solver {solver!r}; use one of {', '.join(SOLVERS)}")
    if solver == "cp-sat":
        require_cpsat()


def _search(inst: Instance, red: Reduced, time_limit: float, coarse: bool | None, say: Callable[[str], None],
            nested: bool = False, solver: str = "highs") -> Optimum:
    t_start = time.perf_counter()
    end = t_start + time_limit
    seconds: dict[str, float] = {}
    history: list[dict[str, Any]] = []

    def mark(phase: str, t: float, best: np.ndarray | None = None, found: str | None = None) -> None:
        seconds[phase] = time.perf_counter() - t
        if best is not None:
            history.append({"after": phase, "routers": int(best.sum()), "found_by": found,
                            "t_s": round(time.perf_counter() - t_start, 3)})

    t = time.perf_counter()
    hop_s, hop_l = hop_bound_straight(inst), hop_bound_lattice(red)
    best = greedy_connected_cover(red.rows, red.links, red.base_linked) if red.rows.shape[0] else np.zeros(red.n, bool)
    source = "greedy"
    mark("greedy", t, best, source)
    say(f"greedy: {int(best.sum())} routers; hop bounds {hop_s} (straight line), {hop_l} (lattice)")
    t = time.perf_counter()
    sc = solve(set_cover(red.rows), red.n, min(0.1 * time_limit, 60.0)) if red.rows.shape[0] else None
    sc_lower = 0 if sc is None else (sc.value if sc.status == "optimal" else _ceil(sc.bound))
    mark("set_cover", t)
    chain = chain_gains(inst, red)
    t = time.perf_counter()
    lp = lp_bound(flow_model(red.rows, red.links, red.base_linked, big_m=int(best.sum()), chain=chain),
                  min(0.1 * time_limit, 60.0)) if best.any() else 0.0
    mark("lp_relaxation", t)
    say(f"coverage alone: {sc_lower} routers; LP relaxation {lp}")
    coarse_info = None
    use_coarse = (red.n > COARSE_FROM) if coarse is None else coarse
    if use_coarse and not nested and best.any():
        t = time.perf_counter()
        start, coarse_info = _coarse(inst, red, 0.25 * time_limit, say, solver)
        if start is not None and start.sum() < best.sum():
            best, source = start, "coarse lattice"
        mark("coarse", t, best, source)
    if best.any():
        t = time.perf_counter()
        model = flow_model(red.rows, red.links, red.base_linked, big_m=int(best.sum()), chain=chain)
        better, windows = improve(model, inst.sites[red.keep], best, min(0.3 * time_limit, end - time.perf_counter()))
        if better.sum() < best.sum():
            best, source = better, "local search"
        mark("local_search", t, best, source)
        say(f"local search: {int(best.sum())} routers ({windows} windows)")
    t = time.perf_counter()
    sat_lower, sat_run = 0, None
    if best.any() and solver == "cp-sat":  # CP-SAT's bound search first, then HiGHS from its best
        sat = solve_cpsat(red.rows, red.links, red.base_linked, CPSAT_SHARE * max(end - time.perf_counter(), 0.5),
                          start=best, chain=chain)
        if sat.chosen is not None and sat.value is not None and sat.value < best.sum():
            best, source = sat.chosen, "solver"
        sat_lower = min(_ceil(sat.bound), int(best.sum()))
        sat_run = {"status": sat.status, "seconds": sat.seconds, "branches": sat.nodes, "bound": _finite(sat.bound)}
    if best.any() and sat_lower < best.sum():
        model = flow_model(red.rows, red.links, red.base_linked, big_m=int(best.sum()) - 1, chain=chain)
        res = solve(model, red.n, max(end - time.perf_counter(), 0.5), cutoff=int(best.sum()) - 1,
                    incumbent=int(best.sum()))
        if res.chosen is not None and res.value is not None and res.value < best.sum():
            best, source = res.chosen, "solver"
        proved_best = math.isinf(res.bound) and res.bound > 0  # no better placement exists
        solver_lower = int(best.sum()) if proved_best else min(_ceil(res.bound), int(best.sum()))
        solver_lower = max(solver_lower, min(sat_lower, int(best.sum())))
        status = "optimal" if sat_run is not None and solver_lower >= best.sum() else res.status
        run = {"status": status, "seconds": res.seconds, "nodes": res.nodes, "dual_bound": _finite(res.bound)}
    elif best.any():  # CP-SAT proved the best optimal
        solver_lower = sat_lower
        run = {"status": "optimal", "seconds": 0.0, "nodes": 0, "dual_bound": None}
    else:  # the base stations cover everything: no router is needed
        solver_lower, run = 0, {"status": "optimal", "seconds": 0.0, "nodes": 0, "dual_bound": 0.0}
    mark("solver", t, best, source)
    lower = max(solver_lower, sc_lower, hop_s, hop_l)
    chosen = red.keep[np.flatnonzero(best)]
    routers = inst.sites[chosen]
    if sat_run is not None:
        run["cp_sat"] = sat_run
    say(f"solver: {run['status']}; best {len(routers)}, lower bound {lower}")
    return Optimum(
        map=inst.omap.name, bases=[tuple(map(float, b)) for b in inst.bases_xy], radio=inst.radio,
        spacing=inst.spacing, routers=routers, source=source, lower=lower,
        bounds={"solver": solver_lower, "solver_dual_bound": run["dual_bound"], "lp_relaxation": lp,
                "set_cover": {"lower": sc_lower, "status": "empty" if sc is None else sc.status,
                              "value": None if sc is None else sc.value},
                "hop_straight": hop_s, "hop_lattice": hop_l, "chain_cells": int(chain[1])},
        solver={"name": _solver_name(solver), **run, "time_limit_s": time_limit},
        sample={"cells": int(inst.reachable.sum()), "cell_m": float(inst.omap.resolution),
                "covered_by_bases": int(inst.reachable.sum()) - len(inst.cells),
                "reachable_area_m2": inst.reachable_area_m2},
        candidates={"sites": inst.n_sites, "off_lattice": int(np.isnan(inst.lattice[:, 0]).sum()), "kept": red.n,
                    "rows": int(red.rows.shape[0]), "anchor": list(inst.anchor),
                    "router_radius_m": inst.router_radius, "reductions": red.stats},
        seconds=seconds, verified=verify(inst, chosen), coarse=coarse_info, history=history, instance=inst)


def _ceil(bound: float) -> int:
    """The least integer at least ``bound`` (less a rounding tolerance): counts are whole numbers; 0 if not finite."""
    return int(math.ceil(bound - 1e-6)) if math.isfinite(bound) else 0


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def _coarse(inst: Instance, red: Reduced, budget: float, say: Callable[[str], None], solver: str = "highs"
            ) -> tuple[np.ndarray | None, dict[str, Any] | None]:
    """Search the lattice of twice the spacing; its best placement as a start over the fine kept sites."""
    lat = inst.lattice
    sub = np.isnan(lat[:, 0]) | ((lat[:, 0] % 2 == 0) & (lat[:, 1] % 2 == 0))
    try:
        small = subinstance(inst, sub)
    except AmronetError as exc:
        return None, {"used": False, "why": str(exc)}
    small_red = reduce_instance(small)
    found = _search(small, small_red, budget, False, lambda line: say("  coarse " + line), nested=True,
                    solver=solver)
    idx = np.flatnonzero(sub)
    placed = idx[_site_indices(small, found.routers)]
    start = red.from_instance(placed)
    ok = covers_all(red.rows, start) and connected(red.links, red.base_linked, start)
    start = prune(red.rows, red.links, red.base_linked, start) if ok else None
    info = {"used": True, "spacing_m": 2 * inst.spacing, "sites": int(sub.sum()), "routers": found.count,
            "lower_bound": found.lower, "start_routers": None if start is None else int(start.sum())}
    return start, info


def _site_indices(inst: Instance, xy: np.ndarray) -> np.ndarray:
    """Indices of the sites at the positions ``xy`` (exactly)."""
    where = {tuple(p): i for i, p in enumerate(inst.sites.tolist())}
    return np.array([where[tuple(p)] for p in np.asarray(xy).tolist()], dtype=np.int64)


def subinstance(inst: Instance, mask: np.ndarray) -> Instance:
    """The instance restricted to the sites in ``mask``.

    Raises:
        AmronetError: Some sample cell cannot be covered by a site of ``mask`` linked to a base station.
    """
    links = inst.links[mask][:, mask].tocsr()
    cover = inst.cover[:, mask].tocsr()
    return check_feasible(dataclasses.replace(inst, sites=inst.sites[mask], lattice=inst.lattice[mask], cover=cover,
                                              links=links, base_linked=inst.base_linked[mask]))


def verify(inst: Instance, chosen: np.ndarray) -> dict[str, Any]:
    """A placement (instance site indices) checked by amronet's own code: the coverage a run would report, links.

    Returns:
        ``coverage`` (the fraction of the reachable free space the radio's coverage rule covers, as a run's
        ``coverage``), ``connected`` (every router has a path to a base station in the medium's neighbour table).
    """
    xy = inst.nodes_xy(chosen)
    area = CoverageArea(inst.omap, inst.reachable)
    covered = inst.medium.covered_mask(area, xy)
    table = inst.medium.update(xy)
    nb = len(inst.bases_xy)
    linked = connected_to(table, np.arange(nb))
    return {"coverage": float(covered[inst.reachable].mean()), "connected": bool(linked.all()),
            "uncovered_cells": int((inst.reachable & ~covered).sum())}
