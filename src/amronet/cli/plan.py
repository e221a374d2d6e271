"""The ``amronet plan`` subcommand: how many routers to carry (see :mod:`amronet.planning`).

``amronet plan --map depot --base 1.0,2.0 [--base X,Y ...] --rc 4 --agents 3 [--runs 20] [--confidence 0.95]
[--radio multi-wall [--shadowing-db 4] [--wall-db 6.9]] [--drop-rule link-quality [--drop KEY=VALUE ...]]
[--stock 12 [--when-empty tether|continue]] [--settle-s 3] [--reverse-drop 1] [--trajectories paths.csv]
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
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from amronet.cli.common import add_executor_arguments, make_executor_from_args, parse_base
from amronet.errors import AmronetError

if TYPE_CHECKING:
    from amronet.planning import Mission

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
    if args.optimum is not None and not (math.isfinite(args.optimum) and args.optimum > 0):
        raise AmronetError(f"--optimum: must be a number of seconds > 0, got {args.optimum:g}")
    if args.optimum is not None:
        _check_optimum(args, bases)
    with make_executor_from_args(args) as executor:
        options = RunOptions(explorer=args.explorer, time_limit=args.time_limit, seed=args.seed, store=args.store,
                             executor=executor, show_progress=not args.quiet and not args.json,
                             retry_failed=args.retry_failed)
        p = plan(args.map, bases, r_c=args.rc, agents_per_base=args.agents, runs=args.runs,
                 confidence=args.confidence, options=options, mission=_mission(args))
    if args.optimum is not None:
        p.optimum = _optimum(args, bases)
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
            from amronet.outputs.console import folder_name

            print(f"wrote {folder_name(args.out)}: plan.json plan.md"
                  + (" typical.png" if p.typical_seed is not None else ""))
    for line in p.warnings if not args.json else []:
        print(f"amronet: warning: {line}", file=sys.stderr)
    return 0 if p.recommended is not None else 1


def _check_optimum(args: argparse.Namespace, bases: list[tuple[float, float]]) -> None:
    """``--optimum``: refuse, before any run, an optimum that cannot be solved (its time limit, lattice or radio).

    The problem is built here and again by the solve after the runs (a build is a small part of a solve).
    """
    from amronet.optimum import build_instance
    from amronet.optimum.solve import check_time_limit

    check_time_limit(args.optimum, "--optimum")
    with _lattice_named(args):
        build_instance(args.map, bases, args.rc, args.rc / 2, radio=_mission(args).radio, seed=args.seed)


@contextmanager
def _lattice_named(args: argparse.Namespace) -> Iterator[None]:
    """Turn the optimum's ``--spacing`` errors into ``--optimum`` ones: plan has no --spacing; name its lattice."""
    try:
        yield
    except AmronetError as exc:
        if not str(exc).startswith("--spacing: "):
            raise
        why = str(exc).removeprefix("--spacing: ")
        raise AmronetError(f"--optimum: {why} (plan's lattice is r_c / 2 = {args.rc / 2:g} m; amronet optimum "
                           "--spacing takes a finer one)") from None


def _optimum(args: argparse.Namespace, bases: list[tuple[float, float]]) -> dict[str, Any]:
    """``--optimum SECONDS``: the fewest routers on a lattice of ``r_c / 2``, kept in ``--store`` when given.

    See :func:`amronet.optimum.find_or_load_optimum`.
    """
    from amronet.optimum import find_or_load_optimum

    radio = _mission(args).radio
    with _lattice_named(args):
        opt = find_or_load_optimum(args.map, bases, args.rc, args.rc / 2, radio=radio, seed=args.seed,
                                   time_limit=args.optimum, store=args.store)
    return {"routers": opt.count, "lower_bound": opt.lower, "gap": opt.gap, "optimal": opt.optimal,
            "spacing_m": opt.spacing, "time_limit_s": args.optimum, "solver_status": opt.solver["status"]}


def _mission(args: argparse.Namespace) -> Mission:
    """The radio, drop rule and stock options as :func:`amronet.planning.plan` takes them."""
    from amronet.planning import Mission
    from amronet.scenario import parse_override

    radio: dict[str, Any] = {}
    if args.radio is not None:
        radio["model"] = args.radio
    for option, key in ((args.shadowing_db, "shadowing_db"), (args.wall_db, "wall_db")):
        if option is not None:
            radio[key] = float(option)
    drop: dict[str, Any] = {}
    for item in args.drop or []:
        if "=" not in item or not item.partition("=")[0].strip():
            raise AmronetError(f"--drop: expected KEY=VALUE, got {item!r}; {_drop_keys(args.drop_rule)}")
        try:
            key, value = parse_override(item)
        except AmronetError as exc:
            raise AmronetError(f"--drop: {exc}") from None
        drop[key] = value
    return Mission(radio=radio or None, drop_rule=args.drop_rule, drop=drop or None, stock=args.stock,
                   when_empty=args.when_empty, settle_s=args.settle_s, reverse_drop=args.reverse_drop,
                   trajectories=args.trajectories)


def _drop_keys(rule: str | None) -> str:
    """The keys ``--drop`` takes under the drop rule ``rule`` (``None``: the default), as advice."""
    from amronet.algorithms.agent_assisted.drops import DROP_RULES

    name = rule or "last-reference"
    rule_cls = DROP_RULES.get(name)
    if rule_cls is None:
        return f"and --drop-rule {name!r} is no drop rule; choose one of: " + ", ".join(sorted(DROP_RULES))
    keys = list(rule_cls.Params.model_fields)
    if keys:
        return f"the {name} rule takes: " + ", ".join(keys)
    with_keys = [n for n in sorted(DROP_RULES) if DROP_RULES.get(n).Params.model_fields]
    return f"the {name} rule takes no keys; the rules that take some: {', '.join(with_keys)} (--drop-rule)"


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
    p.add_argument("--radio", help="radio model: unit-disk (default), log-distance or multi-wall")
    p.add_argument("--shadowing-db", type=float, help="shadowing sigma in dB (log-distance, multi-wall)")
    p.add_argument("--wall-db", type=float, help="loss per wall in dB (multi-wall)")
    p.add_argument("--drop-rule", help="the agents' drop rule (default last-reference, the paper's)")
    p.add_argument("--drop", action="append", metavar="KEY=VALUE", help="a drop-rule parameter (repeat)")
    p.add_argument("--stock", type=int, help="routers each agent carries (default unlimited); an agent that runs "
                                             "out goes on and may be cut off unless --when-empty tether")
    p.add_argument("--when-empty", choices=("tether", "continue"),
                   help="what an agent with no router left does (default: continue with --stock, else tether)")
    p.add_argument("--settle-s", type=float, help="seconds before a router put down relays (agents.drop_settle_s)")
    p.add_argument("--reverse-drop", type=float, metavar="S",
                   help="back up and drop after S seconds out of contact (agents.reverse_drop)")
    p.add_argument("--trajectories", metavar="CSV",
                   help="the agents' paths (columns t, agent, x, y): plan a replayed or planned mission")
    p.add_argument("--time-limit", type=float, default=6000.0, help="simulated seconds per run at most")
    p.add_argument("--optimum", type=float, nargs="?", const=60.0, metavar="SECONDS",
                   help="also the fewest routers on a lattice of r_c / 2 (amronet optimum) and the recommendation's "
                        "ratio to it, searched for SECONDS (default 60)")
    p.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--store", help="keep the runs (and the --optimum answer) in this result store and reuse them "
                                   "next time")
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
