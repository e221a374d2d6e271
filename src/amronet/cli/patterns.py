"""The ``amronet patterns`` subcommand: the paper's static regular placements (section 5.1.1, Figs. 5 and 6).

``amronet patterns --area 32x32 --r 4`` prints, for each pattern, its density, the paper's estimate, the
placed count, the exact coverage and whether the placement is connected; ``--map NAME_OR_YAML [--base X,Y]``
places the patterns in a map's free space reachable from the base (all free cells without ``--base``);
``--out FILE`` writes the figure; ``--json`` prints JSON instead of the table. Bad input raises
:class:`amronet.errors.AmronetError` with one line naming the option; so does an area too large for ``--r``
(the resource guard, :func:`amronet.patterns.placement.check_budget`: a lattice that would not fit in memory, or a
search that would take absurdly long without ``--force``).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

from amronet.cli.common import parse_base
from amronet.errors import AmronetError, MapError

__all__ = ["add_parser", "cmd_patterns", "parse_area", "parse_radius"]


def parse_area(text: str) -> tuple[float, float]:
    """Parse ``--area WIDTHxHEIGHT`` in metres, e.g. ``32x32`` or ``30.5x20``.

    Raises:
        AmronetError: Not two finite positive numbers joined by ``x``.
    """
    parts = text.lower().replace("×", "x").split("x")
    try:
        if len(parts) != 2:
            raise ValueError
        w, h = float(parts[0]), float(parts[1])
    except ValueError:
        raise AmronetError(f"--area: {text!r} is not WIDTHxHEIGHT in metres, e.g. 32x32") from None
    if not (math.isfinite(w) and math.isfinite(h) and w > 0 and h > 0):
        raise AmronetError(f"--area: {text!r} must have finite sides > 0, e.g. 32x32")
    return w, h


def parse_radius(text: str) -> float:
    """Parse ``--r`` (metres).

    Raises:
        AmronetError: Not a finite number > 0.
    """
    try:
        r = float(text)
    except ValueError:
        raise AmronetError(f"--r: {text!r} is not a number; give the communication radius in metres, e.g. 4") from None
    if not (math.isfinite(r) and r > 0):
        raise AmronetError(f"--r: {text!r} must be a finite number > 0 (metres)")
    return r


def _area(args: argparse.Namespace, r: float) -> tuple[Any, str]:
    """The area to place in (a prepared PatternArea) and a one-line description of it."""
    import numpy as np

    from amronet.patterns import as_area
    from amronet.world import reachable_free, resolve_map

    if args.map is None:
        if args.base is not None:
            raise AmronetError("--base: only with --map (the base picks the map's reachable free space)")
        w, h = parse_area(args.area if args.area is not None else "32x32")
        try:
            return as_area((w, h), r=r), f"{w:g} m x {h:g} m"
        except ValueError as exc:
            raise AmronetError(f"--area: {exc}") from None
    if args.area is not None:
        raise AmronetError("--area: give either --area or --map, not both")
    omap = resolve_map(args.map)
    if args.base is None:
        mask, where = omap.free, "all free cells"
    else:
        base = parse_base(args.base)
        try:
            mask = reachable_free(omap, np.array(base))
        except MapError as exc:
            raise AmronetError(f"--base: {exc.message}") from None
        where = f"free space reachable from ({base[0]:g}, {base[1]:g})"
    if not mask.any():
        raise AmronetError(f"--map: map '{omap.name}' has no free cells to place in")
    return as_area(omap, mask=mask, r=r), f"map {omap.name}, {where}"


def cmd_patterns(args: argparse.Namespace) -> int:
    """Run ``amronet patterns`` (see the module docstring)."""
    r = parse_radius(args.r)
    if args.steps < 1:
        raise AmronetError(f"--steps: must be >= 1, got {args.steps}")
    if not (0 <= args.tol < 1):
        raise AmronetError(f"--tol: must be in [0, 1), got {args.tol:g}")
    out = Path(args.out) if args.out else None
    if out is not None and out.suffix.lower() not in (".png", ".svg"):
        raise AmronetError(f"--out: {args.out!r} must end in .png or .svg")

    from amronet.patterns import DENSITY, PATTERNS, place_all
    from amronet.patterns.placement import check_budget

    area, what = _area(args, r)
    for name in PATTERNS:  # before any lattice is built: one line naming the options
        check_budget(name, area, r, args.steps, force=args.force, field="--map/--r" if args.map else "--area/--r")
    placements = place_all(area, r, steps=args.steps, tol=args.tol, force=args.force)
    if out is not None:
        from amronet.outputs.files import write_file_atomically
        from amronet.viz.patterns import save_patterns_figure

        write_file_atomically(out, lambda tmp: save_patterns_figure(placements, area, r, tmp))
    if args.json:
        doc = {"area": what, "area_m2": area.area_m2, "r": r, "patterns": [p.to_dict() for p in placements.values()]}
        print(json.dumps(doc, indent=2))
        return 0
    print(f"{what} ({area.area_m2:.1f} m²), r = {r:g} m")
    print(f"{'pattern':<11} {'density':>8} {'estimated':>9} {'placed':>7} {'coverage %':>10}  connected")
    for name, p in placements.items():
        print(f"{name:<11} {DENSITY[name]:>8.3f} {p.estimate:>9d} {p.count:>7d} {100 * p.coverage:>10.3f}  "
              f"{'yes' if p.connected else 'NO'}")  # fmt: skip
    if out is not None:
        print(f"wrote {out}")
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``patterns`` on the ``amronet`` subparsers (sets ``func`` to :func:`cmd_patterns`).

    Returns:
        The subcommand's parser.
    """
    p = subparsers.add_parser(
        "patterns",
        help="static regular placements (r-strip, hexagonal, square, triangular) in an area",
        description="Place the paper's four regular patterns at r = r_c: estimated vs placed counts and coverage.",
    )
    p.add_argument("--area", metavar="WxH", help="rectangle in metres (default 32x32); not with --map")
    p.add_argument("--r", required=True, metavar="R", help="communication radius r_c in metres")
    p.add_argument("--map", metavar="NAME_OR_YAML", help="built-in map name or ROS map_server YAML instead of --area")
    p.add_argument("--base", metavar="X,Y", help="with --map: count only free space reachable from this point")
    p.add_argument("--out", metavar="FILE", help="write the figure (.png or .svg)")
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.add_argument("--steps", type=int, default=16, help="offset grid divisions per lattice cell side (default 16)")
    p.add_argument("--tol", type=float, default=1e-4, help="coverage tie tolerance (default 1e-4)")
    p.add_argument("--force", action="store_true", help="place even when the search would take absurdly long "
                                                        "(more than 2e7 lattice points x candidate offsets)")
    p.set_defaults(func=cmd_patterns)
    return p
