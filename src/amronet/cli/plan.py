"""The ``amronet plan`` subcommand: how many routers to carry (see :mod:`amronet.planning`).

``amronet plan --map depot --base 1.0,2.0 [--base X,Y ...] --rc 4 --agents 3 [--runs 20] [--confidence 0.95]
[--store results.sqlite [--retry-failed]] [--out DIR] [--json]`` prints the paper's estimate, the static patterns
placed on the map and the distribution of routers used by agent-assisted deployment over ``--runs`` seeded runs,
with the recommendation. ``--out DIR`` writes ``plan.json``, ``plan.md`` and ``typical.png`` (the picture is
only ever written with ``--out``; ``--json`` then gives its path as ``picture``). Runs ``--store`` holds as
failed are run again only with ``--retry-failed``, as with ``amronet sweep``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from amronet.cli.common import add_executor_arguments, make_executor_from_args, parse_base
from amronet.errors import AmronetError

__all__ = ["add_parsers", "cmd_plan"]


def cmd_plan(args: argparse.Namespace) -> int:
    """Run ``amronet plan`` (see the module docstring)."""
    from amronet.experiments.options import RunOptions
    from amronet.outputs.files import check_output_folder
    from amronet.planning import plan, write_plan

    keep = _store_in(args.store, args.out)
    if args.out is not None:
        check_output_folder(args.out, keep=keep)
    bases = [parse_base(b) for b in args.base or []]
    if not bases:
        raise AmronetError("--base: give at least one base station as --base X,Y")
    if args.time_limit <= 0 or not math.isfinite(args.time_limit):
        raise AmronetError(f"--time-limit: must be a finite number > 0, got {args.time_limit:g}")
    with make_executor_from_args(args) as executor:
        options = RunOptions(explorer=args.explorer, time_limit=args.time_limit, seed=args.seed, store=args.store,
                             executor=executor, show_progress=not args.quiet and not args.json,
                             retry_failed=args.retry_failed)
        p = plan(args.map, bases, r_c=args.rc, agents_per_base=args.agents, runs=args.runs,
                 confidence=args.confidence, options=options)
    picture = None
    if args.out:
        write_plan(p, args.out, keep=keep)
        if p.typical_seed is not None:
            picture = str(Path(args.out) / "typical.png")
    if args.json:
        print(json.dumps({**p.to_dict(), "picture": picture}, indent=2))
    elif not args.quiet:
        print(p.markdown(picture=None), end="")
        if args.out:
            print(f"wrote {args.out}/: plan.json plan.md" + (" typical.png" if p.typical_seed is not None else ""))
    for line in p.warnings if not args.json else []:
        print(f"amronet: warning: {line}", file=sys.stderr)
    return 0 if p.recommended is not None else 1


def _store_in(store: str | None, out: str | None) -> tuple[str, ...]:
    """The store's file name when ``--store`` lies in the ``--out`` folder (it is kept there), else nothing."""
    if store is None or out is None or Path(store).resolve().parent != Path(out).resolve():
        return ()
    return (Path(store).name,)


def add_parsers(subparsers: argparse._SubParsersAction) -> None:
    """Register ``plan`` on the ``amronet`` subparsers."""
    p = subparsers.add_parser(
        "plan", help="how many routers to carry: estimate, static patterns and agent-assisted runs on a map",
        description="Plan a deployment: the paper's 0.77 A/r² estimate, the static patterns placed on the map, "
                    "and the distribution of routers used by agent-assisted deployment over seeded runs.")
    p.add_argument("--map", required=True, help="built-in map name (amronet maps list) or ROS map_server YAML")
    p.add_argument("--base", action="append", metavar="X,Y", help="a base station (repeat for several)")
    p.add_argument("--rc", type=float, required=True, help="communication radius r_c in metres")
    p.add_argument("--agents", type=int, default=1, help="agents per base station (default 1)")
    p.add_argument("--runs", type=int, default=20, help="seeded agent-assisted runs (default 20)")
    p.add_argument("--confidence", type=float, default=0.95,
                   help="recommend this quantile of the routers used (default 0.95: the 95th percentile)")
    p.add_argument("--explorer", default="frontier", help="agents' exploration strategy (default frontier)")
    p.add_argument("--time-limit", type=float, default=6000.0, help="simulated seconds per run at most")
    p.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--store", help="keep the runs in this result store (and reuse them next time)")
    p.add_argument("--retry-failed", action="store_true",
                   help="run again the runs --store holds as failed (otherwise they stay failed, as with sweep)")
    add_executor_arguments(p)
    p.add_argument("--out", metavar="DIR", help="write plan.json, plan.md and typical.png, the picture of a typical "
                                                "run (replaced atomically); the picture is written only with --out")
    p.add_argument("--json", action="store_true",
                   help="print the plan as JSON (no picture: add --out DIR for typical.png; its path is then the "
                        "JSON's picture field, null otherwise)")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but warnings")
    p.set_defaults(func=cmd_plan)
