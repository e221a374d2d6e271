"""``amronet reproduce failures``: what a network loses when routers fail at once, and what it regains.

On ``office-32x32``, ``autolab`` and ``hospital_section``, a fraction (10, 20, 30 %) of the deployed routers fails at
``fault_at`` (600 s, after deployment has settled: agent-assisted runs reach 99 % coverage within 110-470 s on the
first two), and the run goes on for ``after`` seconds (600). Algorithms: self-spreading (the presets
``self-spreading-office``, 160 routers from four corners at ``r_c`` 4 m, and ``self-spreading-autolab``, 60 routers
at 2 m, on the maps that have one; routers still exploring refill holes by the paper's rules) and agent-assisted
deployment (3 agents from one base station, as in ``reproduce buildings``, frontier explorer; agents repair by their
drop rule with the references they still hear; ``sim.coverage_target: off`` keeps the agents going after 99 %),
alone and with each repair rule: ``algorithm.params.repair: relocate``
(:mod:`amronet.algorithms.agent_assisted.relocate`) and ``repair: retrace``
(:mod:`amronet.algorithms.agent_assisted.retrace`). ``runs`` seeds per cell.

Radios (:data:`RADIOS`): the unit disk (every algorithm), and the multi-wall radio without and with 4 dB of shadowing
(the two repair rules). Behind walls the agents drop by ``link-quality``, the rule that keeps them connected there
(``reproduce buildings``): with the paper's distance rule they lose their link before any fault, and no repair can
restore a network whose agents are cut off already.

Per run: connected coverage just before and just after the fault and at the end, the time until every surviving
agent and deployed router again had a path to a base station, extra routers, the routers moved and how far, the
agents' outages. A figure per radio shows connected coverage over time around the fault, mean and 95 % band per
fraction.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from amronet.experiments.building_cells import BUILDINGS
from amronet.experiments.common import agent_scenario, csv_text, write_outputs
from amronet.experiments.options import RunOptions
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_columns, mean_ci_text

__all__ = ["ALGORITHMS", "MAPS", "RADIOS", "REPAIRS", "run_failures"]

ALGORITHMS = ("self-spreading", "agent-assisted", "agent-assisted-relocate", "agent-assisted-retrace")
"""Self-spreading, and agent-assisted deployment without repair and with each repair rule."""
REPAIRS = {"agent-assisted-relocate": "relocate", "agent-assisted-retrace": "retrace"}
"""The algorithms that repair → their ``algorithm.params.repair``."""
MAPS = ("office-32x32", "autolab", "hospital_section")
SPREADING_PRESETS = {"office-32x32": "self-spreading-office", "autolab": "self-spreading-autolab"}
"""Self-spreading runs on the maps that have a preset of it."""
RADIOS: dict[str, dict[str, Any]] = {
    "unit-disk": {},
    "multi-wall": {"model": "multi-wall"},
    "multi-wall-shadowing": {"model": "multi-wall", "shadowing_db": 4.0},
}
"""Label → radio fields beyond ``r_c``."""
WALL_DROP_RULE = "link-quality"
"""The agents' drop rule under a radio with walls (see the module docstring)."""
RESTORED_WITHIN_S = 120.0
"""The table counts the runs restored within this many seconds of the fault."""
_FIRST_CELLS = tuple((m, "unit-disk", a, f) for m in ("office-32x32", "autolab")
                     for a in ("self-spreading", "agent-assisted", "agent-assisted-relocate") for f in (0.1, 0.2, 0.3))
"""The cells of the first version of the experiment, in its order: their runs keep their seeds."""


def _runs_on(map_name: str, radio: str, algorithm: str) -> bool:
    """Whether the experiment has a cell for ``algorithm`` on ``map_name`` under ``radio``."""
    if algorithm == "self-spreading":
        return radio == "unit-disk" and map_name in SPREADING_PRESETS
    return radio == "unit-disk" or algorithm in REPAIRS


def _cell_index(map_name: str, radio: str, algorithm: str, fraction: float) -> int:
    """A cell's place in the full experiment, which fixes its runs' seeds whatever subset runs.

    The cells of the first version come first, in its order (its table was made with those seeds); then every other
    cell by map, radio, algorithm and fraction (a fraction the defaults do not have goes after them).
    """
    cell = (map_name, radio, algorithm, fraction)
    if cell in _FIRST_CELLS:
        return _FIRST_CELLS.index(cell)
    maps = MAPS + (() if map_name in MAPS else (map_name,))
    fractions = (0.1, 0.2, 0.3) + (() if fraction in (0.1, 0.2, 0.3) else (fraction,))
    order = [c for c in ((m, r, a, f) for m in maps for r in RADIOS for a in ALGORITHMS for f in fractions)
             if c not in _FIRST_CELLS]
    return len(_FIRST_CELLS) + order.index(cell)


def _scenario(algorithm: str, map_name: str, fraction: float, fault_at: float, after: float,
              explorer: str, radio: str = "unit-disk") -> dict[str, Any]:
    from amronet.scenario import load_scenario

    fault = [{"at": float(fault_at), "routers": float(fraction)}]
    limit = float(fault_at + after)
    if algorithm == "self-spreading":
        sc = load_scenario(SPREADING_PRESETS[map_name]).to_dict()
        sc["faults"] = fault
        sc["sim"] = {**sc["sim"], "time_limit": limit, "stop_when_settled": False, "record_every": 50}
        return sc
    b = BUILDINGS[map_name]
    walls = radio != "unit-disk"
    sc = agent_scenario(b.map, b.r_c, (b.base,), 3, explorer, limit, radio=RADIOS[radio] or None,
                        drop_rule=WALL_DROP_RULE if walls else None)
    if algorithm in REPAIRS:
        sc["algorithm"]["params"]["repair"] = REPAIRS[algorithm]
    sc["faults"] = fault
    sc["sim"] = {**sc["sim"], "coverage_target": "off", "record_every": 20}
    return sc


def run_failures(
    out_dir: Path,
    maps: tuple[str, ...] = MAPS,
    algorithms: tuple[str, ...] = ALGORITHMS,
    fractions: tuple[float, ...] = (0.1, 0.2, 0.3),
    runs: int = 20,
    fault_at: float = 600.0,
    after: float = 600.0,
    options: RunOptions | None = None,
    radios: tuple[str, ...] = tuple(RADIOS),
) -> dict[str, Any]:
    """Run the experiment; write ``failures_runs.csv``, ``failures_table.csv``, ``failures.md`` and a figure per radio.

    The figures: ``failures.png`` (unit disk), ``failures-multi-wall.png``, ``failures-multi-wall-shadowing.png``.

    Args:
        out_dir: Output folder (replaced atomically; its result store is kept).
        maps: Maps of :data:`~amronet.experiments.buildings.BUILDINGS` (self-spreading only on ``office-32x32`` and
            ``autolab``).
        algorithms: Of :data:`ALGORITHMS`.
        fractions: Fractions of the deployed routers that fail at once.
        runs: Seeded runs per cell.
        fault_at: When the routers fail, simulated seconds.
        after: How long each run goes on after the fault.
        options: How the runs are made (default :class:`RunOptions`): the agents' ``explorer``; ``seed``: run ``k``
            of cell ``c`` uses ``seed * 100000 + 80000 + c * runs + k``, ``c`` the cell's place in the full
            experiment (:func:`_cell_index`); ``time_limit``, when given, is the length of a run: the fault then
            strikes at ``min(fault_at, time_limit / 2)`` and the rest follows it.
        radios: Labels of :data:`RADIOS`; under the ones with walls only the repair rules run.

    Returns:
        ``{"rows", "table", "markdown"}``.

    Raises:
        AmronetError: An unknown map, algorithm or radio (one line naming it and the known ones).
    """
    options = options or RunOptions()
    _check(maps, algorithms, radios)
    if options.time_limit is not None:
        fault_at = min(fault_at, options.time_limit / 2)
        after = options.time_limit - fault_at
    jobs = []
    for map_name in maps:
        for radio in radios:
            for algorithm in algorithms:
                if not _runs_on(map_name, radio, algorithm):
                    continue
                for fraction in fractions:
                    scenario = _scenario(algorithm, map_name, fraction, fault_at, after, options.explorer, radio)
                    first = options.seed * 100_000 + 80_000 + _cell_index(map_name, radio, algorithm, fraction) * runs
                    for k in range(runs):
                        labels = {"map": map_name, "radio": radio, "algorithm": algorithm, "fraction": fraction,
                                  "run": k}
                        jobs.append({"scenario": scenario, "seed": first + k, "labels": labels, "timeseries": True})
    results = run_jobs(jobs, options, description="failures")
    rows, curves = [], {}
    for res in results:
        lab, s, ts = res["labels"], res["summary"], res["timeseries"]
        event = s["faults"]["events"][0] if s["faults"]["events"] else None
        mission = s.get("mission") or {}
        rows.append({**lab, "seed": res["seed"], "failed": s["faults"]["nodes_failed"],
                     "connected_before": None if event is None else round(event["connected_coverage_before"], 6),
                     "connected_after": None if event is None else round(event["connected_coverage_after"], 6),
                     "connected_end": round(s["connected_coverage"], 6),
                     "restored_after_s": None if event is None else event["restored_after_s"],
                     "extra_routers": s["faults"].get("extra_routers", 0),
                     "routers_moved": s["faults"].get("routers_moved", 0),
                     "repair_distance_m": round(s["faults"].get("repair_distance_m", 0.0), 3),
                     "outages": mission.get("outages"), "wall_time_s": round(s["wall_time_s"], 3)})
        key = (lab["radio"], lab["map"], lab["algorithm"], lab["fraction"])
        curves.setdefault(key, []).append((np.asarray(ts["t"]), np.asarray(ts["connected_coverage"])))
    table = _table(rows)
    markdown = _markdown(table, runs, fault_at, after)
    files: dict[str, bytes | str] = {"failures_runs.csv": csv_text(rows), "failures_table.csv": csv_text(table),
                                     "failures.md": markdown}
    for radio in radios:
        panels = [(m, a) for m in maps for a in algorithms if _runs_on(m, radio, a)]
        if panels:
            files[figure_name(radio)] = _figure(curves, radio, panels, fault_at)
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "markdown": markdown}


def figure_name(radio: str) -> str:
    """The figure of a radio: ``failures.png`` for the unit disk (as before there were others), else with its label."""
    return "failures.png" if radio == "unit-disk" else f"failures-{radio}.png"


def _check(maps: tuple[str, ...], algorithms: tuple[str, ...], radios: tuple[str, ...]) -> None:
    from amronet.errors import AmronetError

    for what, given, known in (("map", maps, tuple(BUILDINGS)), ("algorithm", algorithms, ALGORITHMS),
                               ("radio", radios, tuple(RADIOS))):
        for name in given:
            if name not in known:
                raise AmronetError(f"failures: unknown {what} {name!r}; choose of: {', '.join(known)}")


def _table(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    cells: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        cells.setdefault((r["radio"], r["map"], r["algorithm"], r["fraction"]), []).append(r)
    table = []
    for (radio, map_name, algorithm, fraction), sel in cells.items():
        entry: dict[str, Any] = {"radio": radio, "map": map_name, "algorithm": algorithm, "fraction": fraction,
                                 "runs": len(sel)}
        for name in ("failed", "connected_before", "connected_after", "connected_end", "extra_routers", "routers_moved",
                     "repair_distance_m"):
            values = np.array([np.nan if r[name] is None else r[name] for r in sel], dtype=float)
            entry[f"{name}_mean"], entry[f"{name}_ci95"] = mean_ci(values)
        restored = [r["restored_after_s"] for r in sel if r["restored_after_s"] is not None]
        entry["restored_runs"] = len(restored)
        entry["restored_within_runs"] = sum(t <= RESTORED_WITHIN_S for t in restored)
        entry["restored_median_s"] = float(np.median(restored)) if restored else None
        table.append(entry)
    return table


def _markdown(table: list[dict[str, Any]], runs: int, fault_at: float, after: float) -> str:
    lines = ["# Routers that fail", "",
             f"A fraction of the deployed routers fails at once at t = {fault_at:g} s; {after:g} s follow. "
             f"{runs} runs per cell; connected coverage as mean ± 95 % CI. Restored: runs in which every surviving "
             f"agent and deployed router again had a path to a base station (within {RESTORED_WITHIN_S:g} s of the "
             f"fault, in all), and the median time it took. Behind walls the agents drop by `{WALL_DROP_RULE}`."]
    for radio in RADIOS:
        cells = [e for e in table if e["radio"] == radio]
        if not cells:
            continue
        lines += ["", f"## {radio}", "",
                  "| map | algorithm | fails | routers failed | connected before | just after | 600 s later "
                  f"| restored (≤ {RESTORED_WITHIN_S:g} s / all / runs, median s) | routers added | routers moved "
                  "| distance moved (m) |",
                  "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for e in cells:
            med = "" if e["restored_median_s"] is None else f", {e['restored_median_s']:.1f} s"
            lines.append(
                f"| {e['map']} | {e['algorithm']} | {100 * e['fraction']:g} % | {e['failed_mean']:.1f} | "
                f"{mean_ci_text(100 * e['connected_before_mean'], 100 * e['connected_before_ci95'])} % | "
                f"{mean_ci_text(100 * e['connected_after_mean'], 100 * e['connected_after_ci95'])} % | "
                f"{mean_ci_text(100 * e['connected_end_mean'], 100 * e['connected_end_ci95'])} % | "
                f"{e['restored_within_runs']} / {e['restored_runs']} / {e['runs']}{med} | "
                f"{e['extra_routers_mean']:.1f} | {e['routers_moved_mean']:.1f} | {e['repair_distance_m_mean']:.1f} |")
    return "\n".join(lines) + "\n"


def _figure(curves: dict[tuple, list[tuple[np.ndarray, np.ndarray]]], radio: str,
            panels: list[tuple[str, str]], fault_at: float) -> bytes:
    """Connected coverage over time under ``radio``, mean and 95 % band per fraction; a panel per map and algorithm."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    maps = list(dict.fromkeys(m for m, _ in panels))
    algorithms = list(dict.fromkeys(a for _, a in panels))
    fig = Figure(figsize=(4.2 * len(algorithms), 3.2 * len(maps)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(maps), len(algorithms), squeeze=False)
    fractions = sorted({k[3] for k in curves})
    for i, map_name in enumerate(maps):
        for j, algorithm in enumerate(algorithms):
            ax = axes[i][j]
            if (map_name, algorithm) not in panels:
                ax.set_axis_off()
                continue
            for c, fraction in enumerate(fractions):
                series = curves.get((radio, map_name, algorithm, fraction), [])
                if not series:
                    continue
                t = series[0][0]
                n = min(len(s[1]) for s in series)
                mean, half = mean_ci_columns(np.array([s[1][:n] for s in series]))
                ax.plot(t[:n], 100 * mean, color=f"C{c}", label=f"{100 * fraction:g} % fail")
                ax.fill_between(t[:n], 100 * (mean - half), 100 * (mean + half), color=f"C{c}", alpha=0.2)
            ax.axvline(fault_at, color="0.3", lw=0.8, ls="--")
            ax.set_title(f"{algorithm} on {map_name} ({radio})", fontsize=9)
            ax.set_ylim(0, 102)
            ax.grid(True, alpha=0.3)
            ax.set_xlabel("t (s)")
            if j == 0:
                ax.set_ylabel("connected coverage (%)")
            ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
