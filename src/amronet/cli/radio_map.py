"""The ``amronet radio-map`` subcommand: the predicted signal strength of a few nodes over a map.

``amronet radio-map --map autolab --node 2.5,10 [--node X,Y ...] --radio multi-wall [--set radio.KEY=VALUE ...]
[--r-c 4] [--seed 1] --out signal.png [--dpi N]`` draws the best RSSI (dBm) of the nodes at every free cell of the
map, to scale, with the usable threshold's contour and a colour bar (:mod:`amronet.viz.radiomap`). The radio is
the one a scenario with these ``radio`` fields would run (the scenario's validation, defaults and link budget);
``--seed`` draws its shadowing field as a run with that seed would. Bad input raises
:class:`amronet.errors.AmronetError` with one line naming the option, and nothing is written.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from amronet.cli.common import parse_point
from amronet.errors import AmronetError
from amronet.limits import MAX_SIGNAL_WORK, SIGNAL_CELL_WITHOUT_WALLS, check_work, format_count

__all__ = ["PROGRESS_WORK", "add_parser", "parse_node"]

PROGRESS_WORK = 2 * 10**7
"""Node-cells (see :data:`amronet.limits.MAX_SIGNAL_WORK`) from which a map says how far it is (about 5 s)."""


def parse_node(text: str) -> tuple[float, float]:
    """Parse ``--node X,Y`` (metres).

    Raises:
        AmronetError: Not two finite numbers.
    """
    return parse_point(text, "--node", "2.5,10")


def _number(option: str, text: str | None, *, integer: bool = False) -> float | int | None:
    """A numeric option given as text (so that a bad value is one line, not argparse's usage)."""
    if text is None:
        return None
    try:
        value = int(text) if integer else float(text)
    except ValueError:
        kind = "a whole number" if integer else "a number"
        raise AmronetError(f"{option}: {text!r} is not {kind}") from None
    if not integer and not math.isfinite(value):
        raise AmronetError(f"{option}: {text!r} must be finite")
    return value


def _radio_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The ``radio`` fields from ``--radio``, ``--r-c`` and ``--set radio.KEY=VALUE``."""
    from amronet.scenario import parse_override

    fields: dict[str, Any] = {}
    for item in args.set or []:
        key, value = parse_override(item)
        if not key.startswith("radio.") or key == "radio.":
            raise AmronetError(f"--set: {key!r} is not a radio field; radio-map takes --set radio.KEY=VALUE, "
                               "e.g. radio.wall_db=10")
        fields[key] = value
    if args.radio is not None:
        if "radio.model" in fields:
            raise AmronetError("--set: radio.model and --radio both give the model; give one of the two")
        fields["radio.model"] = args.radio
    r_c = _number("--r-c", args.r_c)
    if r_c is not None:
        if "radio.r_c" in fields:
            raise AmronetError("--set: radio.r_c and --r-c both give the range; give one of the two")
        fields["radio.r_c"] = r_c
    return fields


def _progress(work: int, quiet: bool) -> Callable[[int, int], None] | None:
    """How a map of ``work`` node-cells reports its progress on stderr; ``None``: a short map, or ``--quiet``.

    On a terminal one line updated in place; elsewhere (a log, a pipe) a line at each quarter.
    """
    if quiet or work < PROGRESS_WORK:
        return None
    live, start, quarter = sys.stderr.isatty(), time.perf_counter(), [1]

    def report(done: int, total: int) -> None:
        line = f"radio map: {done} of {total} nodes ({time.perf_counter() - start:.0f} s)"
        if live:
            print(f"\r  {line}", end="\n" if done == total else "", file=sys.stderr, flush=True)
        elif done < total and 4 * done >= quarter[0] * total:
            quarter[0] = 4 * done // total + 1
            print(line, file=sys.stderr, flush=True)

    return report


def _cmd_radio_map(args: argparse.Namespace) -> int:
    import numpy as np

    from amronet.outputs.files import write_file_atomically
    from amronet.scenario import load_scenario
    from amronet.sim.assemble import build_medium
    from amronet.viz.decorations import save_figure
    from amronet.viz.radiomap import radio_map_figure
    from amronet.viz.signal import SPAN_DB
    from amronet.world.builtin import resolve_map

    out = Path(args.out)
    fmt = out.suffix.lower().lstrip(".")
    if fmt not in ("png", "svg"):
        raise AmronetError(f"--out: {args.out!r} must end in .png or .svg")
    dpi = _number("--dpi", args.dpi)
    if not 10 <= dpi <= 1200:
        raise AmronetError(f"--dpi: {dpi:g} must be a number between 10 and 1200, e.g. 150")
    seed = _number("--seed", args.seed, integer=True)
    if seed < 0:
        raise AmronetError(f"--seed: {seed} must be a whole number >= 0")
    if not args.node:
        raise AmronetError("--node: give at least one node, e.g. --node 2.5,10")
    nodes = np.array([parse_node(text) for text in args.node], dtype=float)
    radio = _radio_overrides(args)
    omap = resolve_map(args.map)
    inside, free = omap.inside(nodes), omap.is_free(nodes)
    for (x, y), ok_in, ok_free in zip(nodes, inside, free, strict=True):
        if not ok_in:
            x0, x1, y0, y1 = omap.extent
            raise AmronetError(f"--node: ({x:g}, {y:g}) is outside the map {omap.name} [{x0:g}, {x1:g}] x "
                               f"[{y0:g}, {y1:g}]; give a point inside it")
        if not ok_free:
            raise AmronetError(f"--node: ({x:g}, {y:g}) is in a wall or unknown space of {omap.name}; move it to "
                               "free space")
    scenario = load_scenario({"name": "radio-map", "map": omap.name,
                              "base_stations": [{"x": float(nodes[0, 0]), "y": float(nodes[0, 1])}]}, radio)
    medium = build_medium(scenario, omap, np.random.default_rng(seed), packet_loss=False)
    reach = medium.signal_reach(-SPAN_DB)
    cells = medium.heard.cells_in_reach(omap, nodes, reach)
    walls = medium.hearing.wall_db > 0
    work = cells if walls else cells * SIGNAL_CELL_WITHOUT_WALLS
    check_work(work, MAX_SIGNAL_WORK, "--node",
               f"{len(nodes)} nodes x the cells within {min(reach, math.hypot(*omap.size_m)):.3g} m of each = "
               f"{format_count(cells)} node-cells{'' if walls else ' (counted at an eighth: no walls)'}",
               "give fewer --node points", args.force, error=AmronetError, acknowledge="or acknowledge it with --force")
    budget = medium.budget
    threshold = budget.threshold_dbm
    signal = medium.signal_dbm(omap, nodes, floor_db=-SPAN_DB, progress=_progress(work, args.quiet))
    model = scenario.radio.model
    walls = f", {budget.wall_db:g} dB per wall" if budget.wall_db > 0 else ""
    shadowing = f", shadowing {budget.shadowing_db:g} dB (seed {seed})" if budget.shadowing_db > 0 else ""
    title = (f"{omap.name}: {model} radio, r_c = {budget.r_c:g} m, n = {budget.exponent:g}{walls}{shadowing}\n"
             f"best RSSI of {len(nodes)} node{'s' * (len(nodes) != 1)}; usable threshold {threshold:.1f} dBm")
    fig = radio_map_figure(omap, nodes, signal, threshold, title=title, dpi=dpi)
    write_file_atomically(out, lambda tmp: save_figure(fig, tmp, fmt, dpi, facecolor="white"))
    if not args.quiet:
        heard = np.isfinite(signal) & (signal >= threshold) & omap.free
        share = np.count_nonzero(heard) / max(np.count_nonzero(omap.free), 1)
        print(f"radio map of {len(nodes)} node{'s' * (len(nodes) != 1)} on {omap.name} ({model}, threshold "
              f"{threshold:.1f} dBm; usable signal on {100 * share:.1f} % of the free space) -> {out}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``radio-map`` on the ``amronet`` subcommand parser."""
    p = sub.add_parser(
        "radio-map", help="draw the predicted signal strength (dBm) of nodes over a map",
        description="Draw the best received signal strength (RSSI, dBm) of the given nodes at every free cell of a "
                    "map, to scale, with the usable threshold's contour and a colour bar. The radio is the one a "
                    "scenario with these radio fields would run.")
    p.add_argument("--map", required=True, help="built-in map name or ROS map_server YAML")
    p.add_argument("--node", action="append", metavar="X,Y", help="a node's position in metres (repeat for more)")
    p.add_argument("--radio", metavar="MODEL", help="radio model: unit-disk (default), log-distance, multi-wall")
    p.add_argument("--set", action="append", metavar="radio.KEY=VALUE",
                   help="a radio field, e.g. radio.wall_db=10 or radio.shadowing_db=4")
    p.add_argument("--r-c", metavar="METRES", help="median range without walls and shadowing (default 1)")
    p.add_argument("--seed", default="0", help="seed of the shadowing field, as a run's (default 0)")
    p.add_argument("--out", required=True, help="picture to write (.png or .svg)")
    p.add_argument("--dpi", default="150", help="resolution (default 150)")
    p.add_argument("--force", action="store_true", help="draw even when the map would take absurdly long (more "
                   f"than {MAX_SIGNAL_WORK:.0e} nodes x cells within their signal reach)")
    p.add_argument("-q", "--quiet", action="store_true")
    p.set_defaults(func=_cmd_radio_map)
