"""The ``amronet optimum`` subcommand: the fewest routers that could cover a building, with a proven bound.

``amronet optimum --map office-32x32 --base 1,1 [--base X,Y ...] --rc 4 [--spacing 2] [--radio multi-wall
[--wall-db 6.9] [--shadowing-db 4 --seed 0]] [--time-limit 60] [--no-coarse] [--solver highs|cp-sat] [--store S]
[--out DIR] [--json] [-q]``
prints the best placement found, the proven lower bound, the gap and the bounds that explain it (see
:mod:`amronet.optimum`); ``--out DIR`` writes ``optimum.json`` and ``optimum.png`` (replaced atomically, an amronet
output folder); ``--store S`` keeps the answer in a result store and loads it the next time the same problem is
asked (:mod:`amronet.optimum.stored`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from amronet.cli.common import parse_base
from amronet.errors import AmronetError

__all__ = ["add_parser", "cmd_optimum"]


def cmd_optimum(args: argparse.Namespace) -> int:
    """Run ``amronet optimum`` (see the module docstring)."""
    from amronet.optimum import find_or_load_optimum, write_optimum
    from amronet.outputs.files import check_output_folder
    from amronet.sweeps.store import check_store_path

    if args.out is not None:  # before the search: a folder holding a user's files is refused, untouched
        check_output_folder(args.out)
    if args.store is not None:  # likewise a file that is not an amronet store
        check_store_path(Path(args.store))
    bases = [parse_base(b) for b in args.base or []]
    if not bases:
        raise AmronetError("--base: give at least one base station as --base X,Y")
    spacing = args.spacing if args.spacing is not None else args.rc / 2
    if not math.isfinite(args.rc) or args.rc <= 0:
        raise AmronetError(f"--rc: must be a finite number > 0 (metres), got {args.rc:g}")
    radio = {}
    if args.radio is not None:
        radio["model"] = args.radio
    for value, key in ((args.wall_db, "wall_db"), (args.shadowing_db, "shadowing_db")):
        if value is not None:
            radio[key] = value
    quiet = args.quiet or args.json

    def log(line: str) -> None:
        if not quiet:
            print(f"  {line}", file=sys.stderr, flush=True)

    opt = find_or_load_optimum(args.map, bases, args.rc, spacing, radio=radio or None, seed=args.seed,
                               time_limit=args.time_limit, coarse=False if args.no_coarse else None,
                               solver=args.solver, store=args.store, instance=args.out is not None, log=log)
    if args.out is not None:
        write_optimum(opt, args.out)
    if args.json:
        print(json.dumps(opt.to_dict(), indent=2))
    elif not args.quiet:
        print(opt.text(), end="")
        if args.out is not None:
            from amronet.outputs.console import folder_name

            print(f"wrote {folder_name(args.out)}: optimum.json optimum.png")
    return 0


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``optimum`` on the ``amronet`` subparsers."""
    p = subparsers.add_parser(
        "optimum", help="the fewest routers that could cover a map, with a proven lower bound (integer program)",
        description="The fewest routers on a lattice of candidate sites that cover the reachable free space and "
                    "connect to the base stations, by an integer program (HiGHS) under a time limit: the best "
                    "placement found, a proven lower bound, the gap between them, and the bounds that explain it.")
    p.add_argument("--map", required=True, help="built-in map name (amronet maps list) or ROS map_server YAML")
    p.add_argument("--base", action="append", metavar="X,Y", help="a base station (repeat for several)")
    p.add_argument("--rc", type=float, required=True, help="communication radius r_c in metres")
    p.add_argument("--spacing", type=float, help="distance between candidate sites in metres (default r_c / 2); "
                                                 "finer is closer to routers anywhere, and harder")
    p.add_argument("--radio", help="radio model: unit-disk (default), log-distance or multi-wall")
    p.add_argument("--wall-db", type=float, help="loss per wall in dB (multi-wall)")
    p.add_argument("--shadowing-db", type=float, help="shadowing sigma in dB (log-distance, multi-wall)")
    p.add_argument("--seed", type=int, default=0, help="seed of the shadowing field, as a run's (default 0)")
    p.add_argument("--time-limit", type=float, default=60.0,
                   help="seconds for the search, heuristics and solver (default 60); the bound proven by then is "
                        "reported")
    p.add_argument("--no-coarse", action="store_true",
                   help="do not search the lattice of twice the spacing first (done on large lattices)")
    p.add_argument("--solver", default="highs",
                   help="the last phase's solver: highs (default, scipy) or cp-sat (OR-Tools CP-SAT for half of it, "
                        "then HiGHS; an optional extra: pip install 'amronet[optimum]'; proves higher bounds on "
                        "open floors)")
    p.add_argument("--out", metavar="DIR", help="write optimum.json and optimum.png (replaced atomically)")
    p.add_argument("--store", metavar="S", help="result store: keep the answer, and load it instead of solving when "
                                                "the same problem (map, bases, radio, spacing, time limit) was solved")
    p.add_argument("--json", action="store_true", help="print the answer as JSON (no progress lines)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    p.set_defaults(func=cmd_optimum)
