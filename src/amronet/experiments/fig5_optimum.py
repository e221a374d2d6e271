"""Fig. 5 against the optimum (``reproduce fig5 --optimum``): each count as a ratio to the lattice optimum.

Per map and ``r_c``: the fewest routers found on a lattice of candidate sites, its proven bound, and each
algorithm's count as a ratio to both. The optimum (:mod:`amronet.optimum`) is solved for one base station at the
first start location, the corner (1, 1), under the figure's radio (the unit disk of radius ``r_c``), on a lattice
of ``r_c / 2`` unless told otherwise, within a time limit per problem, through the result store: a rerun loads it
instead of solving again. Counts are compared as the figure draws them, with the base node: the optimum's routers
plus its base station.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from amronet.experiments.common import START_LOCATIONS
from amronet.optimum import CAVEAT, Optimum, find_or_load_optimum
from amronet.optimum.solve import check_time_limit

__all__ = ["OPTIMUM_BASE", "add_optimum", "optimum_markdown", "solve_optima"]

OPTIMUM_BASE = START_LOCATIONS[0]
"""The optimum's base station: the first of Fig. 5's start locations, a corner."""


def solve_optima(maps: Sequence[str], radii: Sequence[float], time_limit: float, spacing: float | None,
                 store: str | Path | None, show_progress: bool) -> dict[tuple[str, float], Optimum]:
    """The optimum of every map and radius, loaded from ``store`` when solved before, else solved and kept there.

    Args:
        maps: The floors.
        radii: The radii ``r_c`` (m).
        time_limit: Seconds of search per problem.
        spacing: The candidate lattice's spacing (m); ``None``: ``r_c / 2`` for each radius.
        store: The result store (``None``: solve, keep nothing).
        show_progress: Say each answer on stderr.

    Raises:
        AmronetError: ``time_limit`` or ``spacing`` is bad (one line naming ``--optimum`` or ``--spacing``).
    """
    check_time_limit(time_limit, "--optimum")
    out = {}
    for map_name in maps:
        for r in radii:
            opt = find_or_load_optimum(map_name, [OPTIMUM_BASE], float(r), spacing if spacing is not None else r / 2,
                                       time_limit=time_limit, store=store)
            if show_progress:
                how = "from the store" if opt.from_store else f"{opt.seconds['total']:.0f} s"
                print(f"optimum {map_name}, r_c {r:g} m: {opt.count} routers, proven bound {opt.lower} ({how})",
                      file=sys.stderr, flush=True)
            out[(map_name, float(r))] = opt
    return out


def add_optimum(table: list[dict[str, Any]], optima: dict[tuple[str, float], Optimum], names: Sequence[str]) -> None:
    """Add the optimum's columns to Fig. 5's table (in place) and each count's ratio to its best and its bound.

    Args:
        table: Fig. 5's per-(map, r_c) entries (``ard_mean``, ``{pattern}_placed``).
        optima: :func:`solve_optima`'s answers.
        names: The patterns whose placed counts are compared.
    """
    for e in table:
        opt = optima[(e["map"], e["r_c"])]
        best, bound = opt.count + len(opt.bases), opt.lower + len(opt.bases)
        e.update({"opt_best_nodes": best, "opt_bound_nodes": bound,
                  "opt_gap": None if opt.gap is None else round(opt.gap, 6), "opt_optimal": opt.optimal,
                  "opt_spacing_m": opt.spacing, "opt_time_limit_s": opt.solver["time_limit_s"]})
        for name, count in (("ard", e["ard_mean"]), *((n, e[f"{n}_placed"]) for n in names)):
            e[f"{name}_to_opt_best"] = count / best
            e[f"{name}_to_opt_bound"] = count / bound


def _ratios(e: dict[str, Any], name: str) -> str:
    lo, hi = e[f"{name}_to_opt_best"], e[f"{name}_to_opt_bound"]
    if math.isnan(lo):
        return "n/a"
    return f"{lo:.2f}x" if e["opt_optimal"] else f"{lo:.2f}x / {hi:.2f}x"


def optimum_markdown(table: list[dict[str, Any]], names: Sequence[str], short: dict[str, str]) -> str:
    """The section of ``fig5_claims.md`` that compares every count with the optimum, with the caveat in words.

    Args:
        table: The entries :func:`add_optimum` completed.
        names: The patterns compared.
        short: A pattern's column title (``r-strip`` → ``RSTR``).
    """
    x, y = OPTIMUM_BASE
    limits = sorted({e["opt_time_limit_s"] for e in table})
    lines = [
        "## Against the optimum", "",
        f"Counts include the base node: the optimum's are its routers and one base station at ({x:g}, {y:g}). "
        "*best* is the fewest found on a lattice of candidate sites (*spacing* apart) within "
        f"{', '.join(f'{t:g}' for t in limits)} s of search per problem, *bound* the lower bound proven for that "
        "lattice and coverage sample. Each count is given as a ratio to the best and to the bound (x / y): its "
        "distance from the lattice optimum lies between the two (one number when the optimum is proven).", "",
        "| map | r_c | spacing | optimum best / bound (gap) | ARD mean | " + " | ".join(short[n] for n in names)
        + " |", "|---|---:|---:|---:|---:|" + "---:|" * len(names)]
    for e in table:
        gap = "optimal" if e["opt_optimal"] else ("gap unbounded" if e["opt_gap"] is None
                                                  else f"gap {100 * e['opt_gap']:.1f} %")
        lines.append(f"| {e['map']} | {e['r_c']:g} | {e['opt_spacing_m']:g} | {e['opt_best_nodes']} / "
                     f"{e['opt_bound_nodes']} ({gap}) | {_ratios(e, 'ard')} | "
                     + " | ".join(_ratios(e, n) for n in names) + " |")
    lines += ["", f"Caveat: {CAVEAT} The optimum covers every reachable cell from the one base station; ARD stops at "
                  "99 % coverage and starts from five locations, and the static patterns cover the open 32 m square "
                  "whatever its walls, so any of them may need fewer nodes than the lattice optimum (a ratio below "
                  "1)."]
    return "\n".join(lines) + "\n"
