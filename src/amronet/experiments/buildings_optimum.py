"""The buildings against the optimum (``reproduce buildings --optimum``): each rule's relays as a ratio to it.

Per building and radio: the fewest routers found on a lattice of candidate sites (:mod:`amronet.optimum`) that
cover the free space the building's base station reaches and stay connected to it, the lower bound proven for that
lattice, and every cell's mean relays used as a ratio to both. The optimum is solved for the experiment's base
station and ``r_c`` (:data:`~amronet.experiments.buildings.BUILDINGS`), within a time limit per problem, through
the result store: a rerun loads it instead of solving again. The lattice is ``r_c / 2`` unless told otherwise; where
walls cut its links so that no placement on it can cover the building (most buildings under the multi-wall radio),
the default goes finer, ``r_c / 4`` then ``r_c / 8``, and says so (a spacing given is kept, or refused).

**Radios with shadowing.** The optimum needs links that do not change from run to run; shadowing draws a new field
for every run's seed. For such a radio (the experiment's ``multi-wall`` with 4 dB of shadowing) the optimum is
solved for its mean path loss, the same radio with the shadowing set to 0 dB (walls and distance only): the
optimum of the average channel, not a bound for any one run (shadowing lengthens some links and shortens others).

Counts are routers, without the base station, as ``relays_used`` counts them. The lattice best is an upper bound
on the true optimum, so the ratio to it understates how far a rule is from the optimum; the ratio to the bound is
the other side: the rule's distance from the lattice optimum lies between the two.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError
from amronet.experiments.building_cells import BUILDINGS, RADIOS, Building
from amronet.experiments.options import check_optimum_options
from amronet.optimum import CAVEAT, Optimum, find_or_load_optimum
from amronet.optimum.stored import optimum_key, optimum_problem
from amronet.sweeps.store import ResultStore

__all__ = ["REFINE", "add_building_optimum", "building_optimum_markdown", "optimum_radio", "solve_building_optima"]

REFINE = 3
"""Spacings tried by default, each half the last: ``r_c / 2``, ``r_c / 4``, ``r_c / 8``."""


def optimum_radio(label: str) -> tuple[dict[str, Any] | None, str]:
    """The deterministic radio the optimum of :data:`RADIOS`' ``label`` is solved for, and how it is named.

    Returns:
        ``(radio fields beyond r_c or None for the unit disk, its name in the table)``: a radio with shadowing
        loses it (its mean path loss).
    """
    radio = dict(RADIOS[label])
    if radio.get("shadowing_db"):
        radio["shadowing_db"] = 0.0
        return radio, f"{label}, mean path loss"
    return radio or None, label


def solve_building_optima(buildings: Sequence[str], radios: Sequence[str], time_limit: float,
                          spacing: float | None, store: str | Path | None,
                          show_progress: bool) -> dict[tuple[str, str], Optimum]:
    """The optimum of every building and radio, loaded from ``store`` when solved before, else solved and kept there.

    Args:
        buildings: Maps of :data:`BUILDINGS`.
        radios: Labels of :data:`RADIOS`.
        time_limit: Seconds of search per problem.
        spacing: The candidate lattice's spacing (m); ``None``: ``r_c / 2`` of each building, or finer (``r_c / 4``,
            then ``r_c / 8``) where no placement on it can cover the building (walls that cut the lattice's links).
        store: The result store (``None``: solve, keep nothing).
        show_progress: Say each answer (and how a radio with shadowing is solved) on stderr.

    Raises:
        AmronetError: ``time_limit`` or ``spacing`` is bad, or the lattice is too coarse to cover a building (one
            line naming ``--optimum`` or ``--optimum-spacing``).
    """
    check_optimum_options(time_limit, spacing)

    def say(line: str) -> None:
        if show_progress:
            print(line, file=sys.stderr, flush=True)

    say(f"optimum: {len(buildings) * len(radios)} problems (building x radio), up to {time_limit:g} s each"
        + (f", kept in {store}" if store is not None else ""))
    for label in radios:
        if optimum_radio(label)[1] != label:
            say(f"optimum, {label}: its shadowing differs from run to run, so the optimum is solved for its mean path "
                f"loss (shadowing 0 dB)")
    out = {}
    for map_name in buildings:
        b = BUILDINGS[map_name]
        for label in radios:
            ladder = (spacing,) if spacing is not None else tuple(b.r_c / 2**k for k in range(1, 1 + REFINE))
            opt = _solve(b, label, ladder, time_limit, store, say)
            how = "from the store" if opt.from_store else f"{opt.seconds['total']:.0f} s"
            say(f"optimum {map_name}, r_c {b.r_c:g} m, {label}: {opt.count} routers, proven bound {opt.lower}, "
                f"{opt.spacing:g} m lattice ({how})")
            out[(map_name, label)] = opt
    return out


def _solve(b: Building, label: str, ladder: tuple[float, ...], time_limit: float, store: str | Path | None,
           say: Callable[[str], None]) -> Optimum:
    """The optimum on the first spacing of ``ladder`` whose lattice can cover the building (the store's first)."""
    radio = optimum_radio(label)[0]
    ladder = ladder[ladder.index(_stored(b, radio, ladder, time_limit, store) or ladder[0]):]
    for k, s in enumerate(ladder):
        try:
            return find_or_load_optimum(b.map, [b.base], b.r_c, s, radio=radio, time_limit=time_limit, store=store)
        except AmronetError as exc:  # a lattice too coarse (or too fine): a finer one, or the option reproduce takes
            text = str(exc)
            if not text.startswith("--spacing: "):
                raise
            why = text.removeprefix("--spacing: ")
            if k + 1 == len(ladder):
                tried = "" if len(ladder) == 1 else f" (tried {', '.join(f'{t:g}' for t in ladder)} m)"
                raise AmronetError(f"--optimum-spacing: {b.map}, {label}: {why}{tried}") from None
            say(f"optimum {b.map}, {label}: {why}; trying {ladder[k + 1]:g} m")
    raise AssertionError("unreachable: the ladder is not empty")  # pragma: no cover


def _stored(b: Building, radio: dict[str, Any] | None, ladder: tuple[float, ...], time_limit: float,
            store: str | Path | None) -> float | None:
    """The first spacing of ``ladder`` whose optimum ``store`` holds (a rerun skips the lattices found too coarse)."""
    if store is None or not Path(store).exists():
        return None
    with ResultStore(store) as rs:
        for s in ladder:
            problem = optimum_problem(b.map, [b.base], b.r_c, s, radio=radio, time_limit=time_limit)
            if rs.stored_optimum(optimum_key(problem)) is not None:
                return s
    return None


def _ratio(count: float, by: int) -> float:
    return count / by if by > 0 else math.nan


def add_building_optimum(table: list[dict[str, Any]], optima: dict[tuple[str, str], Optimum]) -> None:
    """Add the optimum's columns to the buildings table (in place) and each cell's relays as a ratio to them.

    Columns: ``optimum_best`` and ``optimum_bound`` (routers), ``optimum_gap``, ``optimum_optimal``,
    ``optimum_radio``, ``optimum_spacing_m``, ``optimum_time_limit_s``, ``relays_to_optimum_best`` (the cell's
    mean relays used / best) and ``relays_to_optimum_bound`` (/ bound; NaN when the divisor is 0).

    Args:
        table: The per-(map, rule, radio, stock) entries of the buildings table.
        optima: :func:`solve_building_optima`'s answers.
    """
    for e in table:
        opt = optima[(e["map"], e["radio"])]
        e.update({"optimum_best": opt.count, "optimum_bound": opt.lower,
                  "optimum_gap": None if opt.gap is None else round(opt.gap, 6), "optimum_optimal": opt.optimal,
                  "optimum_radio": optimum_radio(e["radio"])[1], "optimum_spacing_m": opt.spacing,
                  "optimum_time_limit_s": opt.solver["time_limit_s"],
                  "relays_to_optimum_best": _ratio(e["relays_mean"], opt.count),
                  "relays_to_optimum_bound": _ratio(e["relays_mean"], opt.lower)})


def _ratios(lo: float, hi: float, optimal: bool) -> str:
    if math.isnan(lo):
        return "n/a"
    return f"{lo:.2f}x" if optimal or math.isnan(hi) else f"{lo:.2f}x / {hi:.2f}x"


def building_optimum_markdown(table: list[dict[str, Any]], strips: dict[str, int]) -> str:
    """The section of ``buildings.md`` that compares every cell with the optimum, with the caveats in words.

    Args:
        table: The entries :func:`add_building_optimum` completed.
        strips: The static r-strip's routers per building (compared under the unit disk, which it is placed for).
    """
    rules = list(dict.fromkeys(e["rule"] for e in table))
    limits = sorted({e["optimum_time_limit_s"] for e in table})
    lines = [
        "## Against the optimum", "",
        "Routers, base station not counted. *best* is the fewest routers found on a lattice of candidate sites "
        "(*spacing* apart) that cover the free space the base station reaches and stay connected to it, within "
        f"{', '.join(f'{t:g}' for t in limits)} s of search per problem; *bound* is the lower bound proven for that "
        "lattice and coverage sample. Each cell's mean relays used is given as a ratio to the best and to the bound "
        "(x / y, one number when the optimum is proven): the best is an upper bound on the true optimum, so the "
        "ratio to it is the low side of the rule's distance from the optimum, and the ratio to the bound the high "
        "side. The radio with shadowing is compared with the optimum of its mean path loss (shadowing 0 dB), as "
        "shadowing differs from run to run. † not every run reached 99 % coverage: those relays cover less than "
        "the optimum does.", "",
        "| map (r_c) | radio | stock | spacing | optimum best / bound (gap) | " + " | ".join(rules)
        + " | static r-strip |", "|---|---|---:|---:|---:|" + "---:|" * len(rules) + "---:|"]
    keys = dict.fromkeys((e["map"], e["radio"], e["stock"]) for e in table)
    for name, radio, stock in keys:
        sel = {e["rule"]: e for e in table if (e["map"], e["radio"], e["stock"]) == (name, radio, stock)}
        e0 = next(iter(sel.values()))
        gap = "optimal" if e0["optimum_optimal"] else ("gap unbounded" if e0["optimum_gap"] is None
                                                       else f"gap {100 * e0['optimum_gap']:.1f} %")
        cells = []
        for rule in rules:
            e = sel.get(rule)
            cells.append("–" if e is None else _ratios(e["relays_to_optimum_best"], e["relays_to_optimum_bound"],
                                                       e["optimum_optimal"])
                         + ("†" if e is not None and e["reached_target"] < e["runs"] else ""))
        strip = "–"
        if radio == "unit-disk" and name in strips:
            strip = _ratios(_ratio(strips[name], e0["optimum_best"]), _ratio(strips[name], e0["optimum_bound"]),
                            e0["optimum_optimal"])
        lines.append(f"| {name} ({BUILDINGS[name].r_c:g} m) | {e0['optimum_radio']} | {stock} | "
                     f"{e0['optimum_spacing_m']:g} | {e0['optimum_best']} / {e0['optimum_bound']} ({gap}) | "
                     + " | ".join(cells) + f" | {strip} |")
    lines += ["", f"Caveat: {CAVEAT} The runs stop at 99 % coverage and the static r-strip covers the free space "
                  "as an open area, walls or not, so either may need fewer routers than the lattice optimum (a ratio "
                  "below 1)."]
    return "\n".join(lines) + "\n"
