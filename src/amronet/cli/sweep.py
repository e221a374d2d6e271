"""The ``amronet sweep``, ``amronet results`` and ``amronet plot`` subcommands.

* ``amronet sweep SWEEP.yaml --store results.sqlite [--workers N | --scheduler tcp://host:8786 | --cluster local]
  [--worker-timeout SECONDS] [--retry-failed]`` runs every (point, seed) of the sweep that is not in the store
  yet, with a progress bar, and prints a table per point. Exit status 1 when runs of the sweep are recorded as
  failed.
* ``amronet results results.sqlite [--sweep NAME] [--export csv|parquet --out DIR]`` lists sweeps and runs, or
  writes the tidy tables.
* ``amronet plot results.sqlite --x radio.r_c --y nodes_total [--hue algorithm.name] [--out plot.png]`` draws the
  mean and 95 % confidence interval (by default into ``plot-Y-vs-X[-by-HUE].png`` in the current folder).

Bad input (a sweep file, a point whose map or base stations cannot start, a store that is not a store, an
unknown column, ``--workers`` with ``--scheduler``) prints one line and exits with 2, leaving the store as it
was. A worker process that dies or a Dask cluster that goes away mid-sweep is one line too (exit 2); the runs
that finished are in the store, and the same command resumes.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from pathlib import Path
from typing import Any

from amronet.cli.common import add_executor_arguments, make_executor_from_args
from amronet.errors import AmronetError

__all__ = ["add_parsers", "cmd_plot", "cmd_results", "cmd_sweep", "default_plot_name"]


def _console() -> Any:
    from rich.console import Console

    return Console(width=None if sys.stdout.isatty() else 200, highlight=False)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.4g}"
    return "" if value is None else str(value)


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run ``amronet sweep`` (see the module docstring)."""
    from rich.table import Table

    from amronet.sweeps import ResultStore, load_sweep, run_sweep
    from amronet.sweeps.executors import check_worker_timeout
    from amronet.sweeps.store import check_store_path
    from amronet.sweeps.tables import point_summary, run_rows

    sweep = load_sweep(args.sweep, force=args.force)
    check_store_path(Path(args.store))
    check_worker_timeout(args.worker_timeout, dask=args.scheduler is not None or args.cluster is not None)
    with make_executor_from_args(args) as executor:
        if args.worker_timeout is not None:
            executor.worker_timeout = args.worker_timeout
        if not args.quiet:
            print(f"{sweep.name}: {len(sweep.points)} points x {len(sweep.seeds)} seeds = {len(sweep.runs())} runs "
                  f"on {executor.describe()}", file=sys.stderr)
        try:
            report = run_sweep(sweep, args.store, executor, retry_failed=args.retry_failed,
                               show_progress=not args.quiet)
        except KeyboardInterrupt as exc:  # a SweepInterrupted says what the store holds
            print(f"amronet: {exc}" if str(exc) else f"amronet: interrupted; every finished run is in {args.store}: "
                  "run the same command again to finish the sweep", file=sys.stderr)
            return 130
    with ResultStore(args.store, must_exist=True) as store:
        rows = run_rows(store, report.sweep_id)
    failed = sum(r["status"] == "failed" for r in rows)
    if args.json:
        print(json.dumps({"sweep": sweep.name, "sweep_id": report.sweep_id, "runs": report.total,
                          "already_in_store": report.already, "done_now": report.done, "failed_now": report.failed,
                          "failed": failed, "finished_elsewhere": report.elsewhere, "wall_time_s": report.wall_time_s,
                          "points": point_summary(rows, sweep.keys)}, indent=2, default=str))
    elif not args.quiet:
        from amronet.sweeps.point_names import short_keys, value_text
        from amronet.sweeps.stats import mean_ci_text

        table = Table(title=f"{sweep.name} ({args.store})")
        names = short_keys(sweep.keys)  # the point's values under their keys' last names (r_c, triangular)
        for col in (*names.values(), *(["scenario"] if args.hash else []), "runs", "failed",
                    "nodes_total (mean ± 95 % CI)", "coverage %", "connected %", "stop"):
            table.add_column(col, justify="right" if col in ("runs", "failed") or "%" in col else "left")
        for e in point_summary(rows, sweep.keys):
            table.add_row(*(value_text(e[k]) for k in sweep.keys), *([e["scenario_hash"][:12]] if args.hash else []),
                          f"{e['done']}/{e['runs']}", str(e["failed"]),
                          mean_ci_text(e["nodes_total_mean"], e["nodes_total_ci95"]),
                          _fmt(100 * e["coverage_mean"]), _fmt(100 * e["connected_coverage_mean"]), e["stop_reason"])
        _console().print(table)
        elsewhere = f", {report.elsewhere} by another sweep on the store" if report.elsewhere else ""
        print(f"{report.total} runs: {report.already} already in the store, {report.done} done and {report.failed} "
              f"failed now{elsewhere}, in {report.wall_time_s:.1f} s")
    if failed:
        print(f"amronet: {failed} runs of sweep {sweep.name!r} failed (amronet results {args.store} --failed); "
              "run again with --retry-failed to retry them", file=sys.stderr)
        return 1
    return 0


def cmd_results(args: argparse.Namespace) -> int:
    """Run ``amronet results`` (see the module docstring)."""
    from rich.table import Table

    from amronet.outputs.files import check_output_folder
    from amronet.sweeps import ResultStore
    from amronet.sweeps.tables import export_tables

    if (args.export is None) != (args.out is None):
        raise AmronetError("--export: give both --export csv|parquet and --out DIR")
    if args.limit < 0:
        raise AmronetError(f"--limit: {args.limit} must be >= 0 (the number of runs to list; 0 lists them all)")
    with ResultStore(args.store, must_exist=True, option="STORE") as store:
        sweep_id = store.find_sweep(args.sweep) if args.sweep else None
        if args.export:
            check_output_folder(args.out)
            counts = export_tables(store, args.export, args.out, sweep_id)
            from amronet.outputs.console import folder_name

            print(f"wrote {folder_name(args.out)}: " + ", ".join(f"{name} ({n} rows)" for name, n in counts.items()))
            return 0
        sweeps = store.sweeps()
        runs = store.runs(sweep_id)
        links = store.links(sweep_id)
    labels, order = _points(runs, links)
    if args.failed:
        runs = [r for r in runs if r["status"] == "failed"]
    if args.json:
        keep = ("scenario_hash", "seed", "status", "error", "nodes_total", "routers_deployed", "coverage",
                "connected_coverage", "stop_reason", "sim_time_s", "wall_time_s", "finished_at")
        print(json.dumps({"sweeps": sweeps, "runs": [{**{k: r.get(k) for k in keep},
                                                      "point": labels.get((r["scenario_hash"], r["seed"]))}
                                                     for r in runs]}, indent=2))
        return 0
    console = _console()
    st = Table(title=f"sweeps in {args.store}")
    for col in ("id", "name", "created", "runs", "done", "failed", "missing"):
        st.add_column(col, justify="right" if col in ("id", "runs", "done", "failed", "missing") else "left")
    for s in sweeps:
        st.add_row(*(str(s[c]) for c in ("id", "name", "created", "runs", "done", "failed", "missing")))
    console.print(st)
    runs = sorted(runs, key=lambda r: order.get((r["scenario_hash"], r["seed"]), len(order)))  # by point, seed
    shown = runs if args.limit == 0 else runs[: args.limit]
    rt = Table(title="runs" + (f" of sweep {args.sweep}" if args.sweep else "") + (" (failed)" if args.failed else ""))
    for col in ("point", *(["scenario"] if args.hash else []), "seed", "status", "nodes_total", "coverage %", "stop",
                "wall s", "error"):
        rt.add_column(col, justify="right" if col in ("seed", "nodes_total", "coverage %", "wall s") else "left")
    names = _short_names(labels.values())
    for r in shown:
        key = (r["scenario_hash"], r["seed"])
        cov = "" if r["coverage"] is None else f"{100 * r['coverage']:.2f}"
        point = _point_text(labels[key], names) if key in labels else f"scenario {r['scenario_hash'][:12]}"
        rt.add_row(point, *([r["scenario_hash"][:12]] if args.hash else []), str(r["seed"]), r["status"],
                   _fmt(r["nodes_total"]), cov, _fmt(r["stop_reason"]), _fmt(r["wall_time_s"]), _fmt(r["error"]))
    console.print(rt)
    if len(shown) < len(runs):
        print(f"... and {len(runs) - len(shown)} more runs (--limit 0 shows all)")
    return 0


def _points(runs: list[dict[str, Any]], links: list[dict[str, Any]]
            ) -> tuple[dict[tuple[str, int], dict[str, Any]], dict[tuple[str, int], int]]:
    """Each run's point labels and its place in (sweep, point, seed) order, by ``(scenario_hash, seed)``.

    A run in several sweeps takes its first sweep's labels; the runs of one sweep carry their own.
    """
    labels: dict[tuple[str, int], dict[str, Any]] = {}
    order: dict[tuple[str, int], int] = {}
    for link in links:
        key = (link["scenario_hash"], link["seed"])
        labels.setdefault(key, link["labels"])
        order.setdefault(key, len(order))
    for r in runs:
        if r.get("labels") is not None:
            labels[(r["scenario_hash"], r["seed"])] = r["labels"]
    return labels, order


def _short_names(labels: Any) -> dict[str, str]:
    from amronet.sweeps.point_names import short_keys, varied_keys

    return short_keys(varied_keys(labels))


def _point_text(labels: dict[str, Any], names: dict[str, str]) -> str:
    from amronet.sweeps.point_names import point_text

    return point_text(labels, names) or "(one point)"


def default_plot_name(x: str, y: str, hue: str | None = None) -> str:
    """The picture ``amronet plot`` writes without ``--out``: ``plot-Y-vs-X[-by-HUE].png`` in the current folder."""
    parts = [y, "vs", x, *(["by", hue] if hue else [])]
    return "plot-" + "-".join(re.sub(r"[^A-Za-z0-9._]+", "_", p) for p in parts) + ".png"


def cmd_plot(args: argparse.Namespace) -> int:
    """Run ``amronet plot`` (see the module docstring)."""
    from amronet.sweeps import ResultStore
    from amronet.sweeps.plot import save_plot
    from amronet.sweeps.tables import run_rows

    with ResultStore(args.store, must_exist=True, option="STORE") as store:
        sweep_id = store.find_sweep(args.sweep) if args.sweep else None
        if sweep_id is None:
            sweeps = store.sweeps()
            if len(sweeps) == 1:
                sweep_id = sweeps[0]["id"]
        rows = run_rows(store, sweep_id)
    out = args.out or default_plot_name(args.x, args.y, args.hue)
    groups = save_plot(rows, args.x, args.y, out, hue=args.hue, title=args.title)
    points = sum(len(v) for v in groups.values())
    print(f"wrote {out}: {args.y} vs {args.x}" + (f" by {args.hue}" if args.hue else "")
          + f", {points} points from {sum(r['status'] == 'done' for r in rows)} runs")
    return 0


def add_parsers(subparsers: argparse._SubParsersAction) -> None:
    """Register ``sweep``, ``results`` and ``plot`` on the ``amronet`` subparsers."""
    p = subparsers.add_parser("sweep", help="run a sweep (grid of overrides x seeds) into a result store",
                              description="Run every (point, seed) of a sweep file that is not in the store yet.")
    p.add_argument("sweep", help="sweep YAML file")
    p.add_argument("--store", required=True, help="result store (SQLite file; created when missing)")
    add_executor_arguments(p, force=False)
    p.add_argument("--worker-timeout", type=float, metavar="SECONDS",
                   help="with Dask: stop when the scheduler has had no worker for this long (default 300; 0 waits "
                        "forever); the finished runs stay in the store")
    p.add_argument("--retry-failed", action="store_true", help="run again the runs recorded as failed")
    p.add_argument("--json", action="store_true", help="print the summary as JSON (with each point's scenario_hash)")
    p.add_argument("--hash", action="store_true", help="also list each point's scenario hash (its key in the store)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar, no table")
    p.add_argument("--force", action="store_true", help="run a sweep of more than 100 000 points or 1 000 000 runs "
                                                        "(refused otherwise as absurdly long), or start more "
                                                        "--workers than there are cores")
    p.set_defaults(func=cmd_sweep)

    r = subparsers.add_parser("results", help="list the sweeps and runs of a result store, or export them")
    r.add_argument("store", metavar="STORE", help="result store (SQLite file)")
    r.add_argument("--sweep", help="only this sweep (name or id)")
    r.add_argument("--failed", action="store_true", help="only failed runs, with their errors")
    r.add_argument("--limit", type=int, default=20, help="runs to list (default 20; 0 for all)")
    r.add_argument("--export", choices=["csv", "parquet"], help="write tidy tables instead of listing")
    r.add_argument("--out", metavar="DIR", help="folder for --export (replaced atomically)")
    r.add_argument("--json", action="store_true", help="print sweeps and runs as JSON (with each run's "
                                                         "scenario_hash and point)")
    r.add_argument("--hash", action="store_true", help="also list each run's scenario hash (its key in the store)")
    r.set_defaults(func=cmd_results)

    g = subparsers.add_parser("plot", help="plot a metric (mean, 95 %% CI) against a parameter from a result store")
    g.add_argument("store", metavar="STORE", help="result store (SQLite file)")
    g.add_argument("--x", required=True, help="x axis: an override key (radio.r_c), a label or a summary field")
    g.add_argument("--y", required=True, help="y axis: a summary field, e.g. nodes_total or coverage")
    g.add_argument("--hue", help="one line per value of this key, e.g. algorithm.name")
    g.add_argument("--sweep", help="only this sweep (name or id); its labels become columns too")
    g.add_argument("--title", help="title of the plot")
    g.add_argument("--out", help="picture to write (.png, .svg or .pdf; default plot-Y-vs-X[-by-HUE].png in the "
                                 "current folder)")
    g.set_defaults(func=cmd_plot)
