"""The ``amronet`` command line.

Every error a user can cause prints one line ``amronet: error: ...`` on stderr and exits with status 2;
nothing is written then.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

from amronet.cli.common import add_executor_arguments, make_executor_from_args
from amronet.errors import AmronetError
from amronet.version import __version__

__all__ = ["build_parser", "main"]


def _cmd_run(args: argparse.Namespace) -> int:
    from amronet.outputs.files import check_output_folder
    from amronet.scenario import load_scenario, parse_override

    if (args.scenario is None) == (args.preset is None):
        raise AmronetError("run: give either a scenario file or --preset NAME (amronet presets lists them)")
    check_output_folder(args.out)
    overrides = dict(parse_override(item) for item in args.set or [])
    scenario = load_scenario(args.scenario if args.scenario is not None else args.preset, overrides)
    from amronet.sim import Simulation  # numba and scipy: imported once the scenario is accepted

    sim = Simulation(scenario, args.seed, force=args.force, step=args.step)
    quiet = args.quiet
    from amronet.cli.viz import make_recorder

    recorder = make_recorder(args, scenario)

    def progress(t: float, limit: float) -> None:
        if not quiet and sys.stderr.isatty():
            print(f"\r  t = {t:7.1f} s / {limit:g} s", end="", file=sys.stderr, flush=True)

    result = sim.run(progress=progress, recorder=recorder)
    if not quiet and sys.stderr.isatty():
        print(file=sys.stderr)
    if args.no_snapshot:
        snapshot = None
    else:
        from amronet.viz.run_snapshot import run_snapshot_png  # matplotlib: imported only when a picture is drawn

        snapshot = run_snapshot_png(result)
    result.save(args.out, snapshot=snapshot)
    if not quiet:
        from amronet.outputs.console import run_lines, wrote_line

        files = ["summary.json", "timeseries.csv", "network.json", *([] if args.no_snapshot else ["snapshot.png"]),
                 *(["recording.npz"] if recorder.full else [])]
        print("\n".join([*run_lines(result.summary), wrote_line(args.out, files)]))
    return 0


def _cmd_maps_list(args: argparse.Namespace) -> int:
    from amronet.world.builtin import list_builtin_maps

    infos = list_builtin_maps()
    if args.json:
        print(json.dumps([{"name": m.name, "width_m": m.size_m[0], "height_m": m.size_m[1],
                           "resolution": m.resolution, "description": m.description, "licence": m.licence}
                          for m in infos], indent=2))
        return 0
    print(f"{'name':<18} {'size (m)':>13} {'m/cell':>7}  description")
    for m in infos:
        size = f"{_metres(m.size_m[0])} x {_metres(m.size_m[1])}"
        print(f"{m.name:<18} {size:>13} {m.resolution:>7g}  {m.description}")
    return 0


def _cmd_maps_show(args: argparse.Namespace) -> int:
    from amronet.outputs.files import write_file_atomically
    from amronet.viz import save_map_picture
    from amronet.world.builtin import resolve_map

    omap = resolve_map(args.map)
    out = Path(args.out)
    if out.suffix.lower() not in (".png", ".svg"):
        raise AmronetError(f"--out: {args.out!r} must end in .png or .svg")
    write_file_atomically(out, lambda tmp: save_map_picture(omap, tmp))
    w, h = omap.size_m
    print(f"{omap.name}: {_metres(w)} m x {_metres(h)} m at {omap.resolution:g} m/cell -> {out}")
    return 0


def _metres(length: float) -> str:
    """A map's width or height to 0.1 m, as ``maps list`` and ``maps show`` print it.

    Rounded half up from the length to 1e-9 m, so that a size the cells give exactly prints the same however its
    float was computed (307 cells of 0.05 m: ``15.4``).
    """
    return str(Decimal(repr(round(length, 9))).quantize(Decimal("0.1"), rounding=ROUND_HALF_UP))


def _cmd_presets(args: argparse.Namespace) -> int:
    from amronet.scenario import list_presets

    for name, desc in list_presets().items():
        print(f"{name:<30} {desc}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from amronet.sim.bench import run_bench

    report = run_bench(algorithm=args.algorithm, robots=args.robots, steps=args.steps, map_name=args.map,
                       seed=args.seed, r_c=args.rc, force=args.force, step=args.step)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        for key, value in report.items():
            print(f"{key:>26}: {value}")
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from amronet.experiments.common import STORE_FILES
    from amronet.experiments.options import check_optimum_options
    from amronet.experiments.registry import FIGURES, check_options, group
    from amronet.outputs.files import check_output_folder
    from amronet.sweeps.worker_bounds import check_workers

    dask = args.scheduler is not None or args.cluster is not None
    if not dask:  # before anything: each figure's pool checks them again, without --force
        check_workers(args.workers, args.force)
    names = group(args.figure) or [args.figure]
    several = group(args.figure) is not None
    # the run options given on the command line (None: not given, the figure's own default applies); each
    # figure must take each of them: checked before anything runs
    given = {"explorer": args.explorer, "time_limit": args.time_limit, "workers": args.workers,
             "retry_failed": args.retry_failed or None, "optimum": args.optimum,
             "optimum_spacing": args.optimum_spacing, "baselines": args.baselines or None}
    check_options([FIGURES[name] for name in names], given, args.figure if several else "all")
    check_optimum_options(args.optimum, args.optimum_spacing)
    outs = {name: Path(args.out or "runs") / name if several else Path(args.out or f"runs/{name}")
            for name in names}
    for out in outs.values():  # before any run: a folder that holds a user's files is refused, untouched
        check_output_folder(out, keep=STORE_FILES)
    shared = dask or (args.force and args.workers is not None)  # more workers than cores: one pool, forced
    with make_executor_from_args(args) if shared else contextlib.nullcontext() as executor:
        for name, out in outs.items():
            store = Path(args.store) if args.store else out / "results.sqlite"
            report = FIGURES[name].run(out, quick=args.quick, show_progress=not args.quiet, store=store,
                                       executor=executor, **given)
            if not args.quiet:
                print(report["markdown"])
                files = sorted(f.name for f in out.iterdir() if f.name.startswith(name)) if out.is_dir() else []
                written = " ".join(files) or "no figure files"
                print(f"wrote {out}/: {written}; runs in {store}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``amronet`` command's parser, with every subcommand (the CLI reference is generated from it)."""
    p = argparse.ArgumentParser(prog="amronet", description="Build and evaluate Ad-hoc Mobile Router Networks.")
    p.add_argument("--version", action="version", version=f"amronet {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run one scenario with one seed")
    r.add_argument("scenario", nargs="?", help="scenario YAML file")
    r.add_argument("--preset", help="a built-in scenario instead of a file (amronet presets)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--out", required=True, help="output folder (replaced atomically)")
    r.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a field, e.g. radio.r_c=1.5")
    r.add_argument("--no-snapshot", action="store_true", help="skip snapshot.png")
    r.add_argument("--record", action="store_true", help="also write recording.npz (for animate, replay, snapshot)")
    r.add_argument("--record-every", type=int, metavar="K", help="record every K-th step (default sim.record_every)")
    r.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    r.add_argument("--force", action="store_true", help="run even when the resource guard finds it absurdly long "
                                                        "(more than 10^7 steps or 10^9 robot-steps)")
    r.add_argument("--step", choices=("compiled", "reference"), default="compiled",
                   help="compiled (default): sense, decide and move in compiled passes where the algorithm has them; "
                        "reference: phase by phase through the controllers' Python (the same result bit for bit, "
                        "slower)")
    r.set_defaults(func=_cmd_run)

    m = sub.add_parser("maps", help="built-in maps")
    msub = m.add_subparsers(dest="maps_command", required=True)
    ml = msub.add_parser("list", help="list built-in maps with their sizes")
    ml.add_argument("--json", action="store_true")
    ml.set_defaults(func=_cmd_maps_list)
    ms = msub.add_parser("show", help="draw a map (free / occupied / unknown, to scale)")
    ms.add_argument("map", help="built-in map name or ROS map_server YAML")
    ms.add_argument("--out", required=True, help="picture to write (.png or .svg)")
    ms.set_defaults(func=_cmd_maps_show)

    ps = sub.add_parser("presets", help="list built-in scenarios")
    ps.set_defaults(func=_cmd_presets)

    from amronet.cli.patterns import add_parser as add_patterns_parser

    add_patterns_parser(sub)
    from amronet.cli.sweep import add_parsers as add_sweep_parsers

    add_sweep_parsers(sub)
    from amronet.cli.plan import add_parsers as add_plan_parsers

    add_plan_parsers(sub)
    from amronet.cli.viz import add_parsers as add_viz_parsers

    add_viz_parsers(sub)
    from amronet.cli.radio_map import add_parser as add_radio_map_parser

    add_radio_map_parser(sub)
    from amronet.cli.optimum import add_parser as add_optimum_parser

    add_optimum_parser(sub)
    from amronet.cli.radio_fit import add_parser as add_radio_fit_parser

    add_radio_fit_parser(sub)

    rp = sub.add_parser(
        "reproduce", help="run one of the paper's experiments (figures) end to end",
        description="Run one of the paper's experiments (figures) end to end. An option a figure does not take is "
                    "an error, not ignored (e.g. fig10 and fig11 run no agents, so they refuse --explorer). With "
                    "all, every option given goes to every figure, so it must be one that every figure takes "
                    "(all --explorer is refused, before anything runs: reproduce the figures with agents one by "
                    "one instead).")
    from amronet.experiments.registry import FIGURES, GROUPS

    rp.add_argument("figure", choices=[*FIGURES, *GROUPS],
                    help="which figure (all: every one, into OUT/FIGURE; paper: the paper's four, fig5 to fig11)")
    rp.add_argument("--out", help="output folder (default runs/FIGURE)")
    rp.add_argument("--store", help="result store: finished runs are kept and reused (default OUT/results.sqlite)")
    rp.add_argument("--explorer", help="agents' exploration strategy (default frontier; only the figures with "
                                       "agents take it)")
    rp.add_argument("--time-limit", type=float, default=None,
                    help="simulated seconds per run at most (default: the figure's own, 6000 for fig5 and fig7)")
    rp.add_argument("--quick", action="store_true", help="a small subset, for a smoke test")
    rp.add_argument("--optimum", type=float, nargs="?", const=60.0, metavar="SECONDS",
                    help="also the fewest routers on a lattice of r_c / 2 (amronet optimum) per map and r_c "
                         "(buildings: per building and radio), and each algorithm's ratio to it, searched for SECONDS "
                         "each (default 60) and kept in the store (only fig5 and buildings take it)")
    rp.add_argument("--optimum-spacing", type=float, metavar="M",
                    help="the optimum's candidate spacing in metres (default r_c / 2; only with --optimum)")
    rp.add_argument("--baselines", action="store_true",
                    help="also the location-aware Voronoi baselines (VOR, Minimax, Lloyd) as extra lines (only fig10 "
                         "and fig11 take it; they double those figures' runs)")
    rp.add_argument("--retry-failed", action="store_true",
                    help="run again the runs the store holds as failed (otherwise the figure stops at them)")
    add_executor_arguments(rp)
    rp.add_argument("-q", "--quiet", action="store_true")
    rp.set_defaults(func=_cmd_reproduce)

    from amronet.cli.compile import add_parser as add_compile_parser

    add_compile_parser(sub)

    b = sub.add_parser("bench", help="measure robot-steps per second of an algorithm's full step")
    b.add_argument("--algorithm", default="self-spreading")
    b.add_argument("--robots", type=int, default=3000)
    b.add_argument("--steps", type=int, default=500)
    b.add_argument("--map", default="hospital_section")
    b.add_argument("--rc", type=float, default=1.0, help="communication radius (default 1 m)")
    b.add_argument("--seed", type=int, default=0)
    b.add_argument("--json", action="store_true", help="print the report as JSON")
    b.add_argument("--step", choices=("compiled", "reference"), default="compiled",
                   help="time the compiled step (default) or the phase-by-phase reference (see amronet run --step)")
    b.add_argument("--force", action="store_true", help="run even when the resource guard finds it absurdly long "
                                                        "(more than 10^9 robot-steps)")
    b.set_defaults(func=_cmd_bench)
    return p


def _ctrl_c_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The ``KeyboardInterrupt`` that ``exc`` was raised while handling (its context or cause, at any depth)."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def _interrupted(exc: KeyboardInterrupt) -> int:
    """Say that Ctrl-C stopped the command (a ``SweepInterrupted`` says what its store holds); exit status 130."""
    print(f"amronet: {exc}" if str(exc) else "amronet: interrupted; nothing was written", file=sys.stderr)
    return 130


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``amronet`` command."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except AmronetError as exc:
        print(f"amronet: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # a sweep's runs (reproduce): SweepInterrupted says what its store holds
        return _interrupted(exc)
    except BrokenPipeError:
        # the reader of stdout went away (amronet results STORE | head -1): stop quietly, as other tools do;
        # stdout goes to devnull so that flushing it at exit does not raise again
        with contextlib.suppress(AttributeError, OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1  # as rich does when its console meets a closed pipe
    except Exception as exc:
        stop = _ctrl_c_behind(exc)
        if stop is None:
            raise
        return _interrupted(stop)  # a library turned Ctrl-C into an error of its own (numba, stopped mid-compile)

