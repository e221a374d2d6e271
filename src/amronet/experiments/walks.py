"""``amronet reproduce walks``: do local walk rules spread self-spreading routers faster than the paper's random walk?

Self-spreading (paper 4.2) on four floor plans (:data:`WALK_MAPS`: a base station at a free point, a
communication radius and a router count that suit each map; the routers of the ``self-spreading-autolab`` demo:
0.045 m discs at 0.5 m/s with 12 range beams of 0.3 m), for every walk rule
(:mod:`amronet.algorithms.self_spreading.walks`),
the same seeds for every rule. Per run, from its coverage over time: the final coverage (at ``time_limit``, default
1 200 s, or when every router has stopped), the time to 90 % of the run's own final coverage, the time to 90 % of
the random walk's mean final coverage on that map (the same level for every rule), the routers deployed, and whether
every deployed router has a path to a base station.

The walk rules' goal, checked per map: time to 90 % of the final coverage at most a third of the random walk's, final
coverage no lower, routers deployed no more, every deployed router connected.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from amronet.algorithms.self_spreading.walks import WALKS
from amronet.experiments.common import Claim, claims_markdown, csv_text, write_outputs
from amronet.experiments.options import RunOptions
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_text

__all__ = ["WALK_MAPS", "WalkMap", "run_walks", "walk_scenario"]

TIME_LIMIT_S = 1200.0
"""Default simulated seconds per run."""
ROUTER = {"radius": 0.045, "max_speed": 0.5, "sensor_beams": 12, "sensor_range": 0.3}
"""The routers of the autolab demo (``self-spreading-autolab``)."""


@dataclass(frozen=True)
class WalkMap:
    """A floor plan of the experiment: its base station (a free point), ``r_c`` and the routers released."""

    base: tuple[float, float]
    r_c: float
    routers: int


WALK_MAPS: dict[str, WalkMap] = {
    "autolab": WalkMap((2.5, 10.0), 2.0, 60),            # the demo (self-spreading-autolab)
    "hospital_section": WalkMap((3.0, 6.0), 2.5, 90),    # west end
    "office-32x32": WalkMap((1.0, 1.0), 4.0, 70),        # the paper's corner base station
    "cave": WalkMap((-6.4, -6.4), 2.0, 60),              # south-west
}
"""The maps, with base stations at free points that reach most of each map's free space."""


def walk_scenario(map_name: str, walk: str, time_limit: float) -> dict[str, Any]:
    """The self-spreading scenario of one map and walk rule, as plain data."""
    m = WALK_MAPS[map_name]
    return {
        "name": f"self-spreading-{map_name}-{walk}",
        "map": map_name,
        "algorithm": {"name": "self-spreading", "params": {"triangular": "local", "walk": walk}},
        "radio": {"model": "unit-disk", "r_c": m.r_c},
        "base_stations": [{"x": m.base[0], "y": m.base[1], "region": [1.5, 1.5]}],
        "routers": {"count": m.routers, "robot": dict(ROUTER)},
        "sim": {"dt": 0.1, "time_limit": time_limit, "record_every": 10, "coverage_method": "raster"},
    }


def run_walks(
    out_dir: Path,
    maps: tuple[str, ...] = tuple(WALK_MAPS),
    walks: tuple[str, ...] = WALKS,
    runs: int = 20,
    options: RunOptions | None = None,
) -> dict[str, Any]:
    """Run the experiment; write ``walks_runs.csv``, ``walks_table.csv``, ``walks.md`` and ``walks.png``.

    Args:
        out_dir: Output folder (replaced atomically; its result store is kept).
        maps: Maps of :data:`WALK_MAPS`.
        walks: Walk rules (``random`` first: the others are compared with it).
        runs: Seeded runs per map and rule.
        options: How the runs are made (default :class:`RunOptions`): ``time_limit`` (default 1 200 s) and
            ``seed``: run ``k`` uses ``seed * 100000 + 80000 + k`` on every map and for every rule; the others say
            where the runs execute (:func:`run_jobs`). ``explorer`` is not used: no agents.

    Returns:
        ``{"rows", "table", "claims", "markdown"}``.
    """
    options = options or RunOptions()
    time_limit = float(options.time_limit_or(TIME_LIMIT_S))
    walks = ("random", *(w for w in walks if w != "random"))
    jobs = []
    for name in maps:
        for walk in walks:
            scenario = walk_scenario(name, walk, time_limit)
            for k in range(runs):
                jobs.append({"scenario": scenario, "seed": options.seed * 100_000 + 80_000 + k, "timeseries": True,
                             "labels": {"map": name, "walk": walk, "run": k}})
    results = run_jobs(jobs, options, description="walks")
    grid = np.arange(0.0, time_limit + 1e-9, 1.0)
    rows, curves = [], {}
    for res in results:
        lab, s, ts = res["labels"], res["summary"], res["timeseries"]
        t, cov = np.asarray(ts["t"], dtype=float), np.asarray(ts["coverage"], dtype=float)
        curves.setdefault((lab["map"], lab["walk"]), []).append(_hold(t, cov, grid))
        rows.append({**lab, "seed": res["seed"], "coverage": round(float(cov[-1]), 6),
                     "time_to_90pct_s": _first_at(t, cov, 0.9 * cov[-1]),
                     "routers_deployed": s["routers_deployed"],
                     "routers_connected_fraction": round(s["routers_connected_fraction"], 6),
                     "settled_at_s": s["settled_at_s"], "stop_reason": s["stop_reason"],
                     "wall_time_s": round(s["wall_time_s"], 3), "_t": t, "_cov": cov})
    for name in maps:  # the level every rule is timed to on a map: 90 % of the random walk's mean final coverage
        level = 0.9 * float(np.mean([r["coverage"] for r in rows if (r["map"], r["walk"]) == (name, "random")]))
        for r in rows:
            if r["map"] == name:
                r["time_to_random_level_s"] = _first_at(r["_t"], r["_cov"], level)
    for r in rows:
        del r["_t"], r["_cov"]
    table = _table(rows, maps, walks)
    claims = _claims(table, maps, walks)
    markdown = _markdown(table, claims, runs, time_limit)
    files = {"walks_runs.csv": csv_text(rows), "walks_table.csv": csv_text(table), "walks.md": markdown,
             "walks.png": _figure(grid, curves, maps, walks)}
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "claims": claims, "markdown": markdown}


def _hold(t: np.ndarray, values: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Values on ``grid``: the last recorded value at or before each instant (held after the run ended)."""
    idx = np.searchsorted(t, grid, side="right") - 1
    return values[np.clip(idx, 0, len(values) - 1)]


def _first_at(t: np.ndarray, values: np.ndarray, level: float) -> float:
    """First time ``values`` reach ``level`` (``inf`` when never)."""
    hit = np.flatnonzero(values >= level - 1e-12)
    return float(t[hit[0]]) if len(hit) else float("inf")


def _finite_mean_ci(values: list[float]) -> tuple[float, float, int]:
    """Mean and 95 % CI of the finite values, and how many were not finite (never reached)."""
    arr = np.asarray(values, dtype=float)
    ok = arr[np.isfinite(arr)]
    if not len(ok):
        return float("inf"), 0.0, len(arr)
    mean, ci = mean_ci(ok)
    return mean, ci, int(len(arr) - len(ok))


def _table(rows: list[dict[str, Any]], maps: tuple[str, ...], walks: tuple[str, ...]) -> list[dict[str, Any]]:
    table = []
    for name in maps:
        for walk in walks:
            sel = [r for r in rows if (r["map"], r["walk"]) == (name, walk)]
            if not sel:
                continue
            cov, cov_ci = mean_ci(np.array([r["coverage"] for r in sel]))
            dep, dep_ci = mean_ci(np.array([r["routers_deployed"] for r in sel], dtype=float))
            t90, t90_ci, t90_never = _finite_mean_ci([r["time_to_90pct_s"] for r in sel])
            tl, tl_ci, tl_never = _finite_mean_ci([r["time_to_random_level_s"] for r in sel])
            table.append({"map": name, "walk": walk, "runs": len(sel), "coverage_mean": cov, "coverage_ci95": cov_ci,
                          "t90_mean_s": t90, "t90_ci95_s": t90_ci, "t90_never": t90_never,
                          "t_random_level_mean_s": tl, "t_random_level_ci95_s": tl_ci, "t_random_level_never": tl_never,
                          "deployed_mean": dep, "deployed_ci95": dep_ci,
                          "all_connected_runs": sum(r["routers_connected_fraction"] == 1.0 for r in sel),
                          "settled_runs": sum(r["stop_reason"] == "settled" for r in sel)})
    return table


def _cell(table: list[dict[str, Any]], name: str, walk: str) -> dict[str, Any] | None:
    return next((e for e in table if (e["map"], e["walk"]) == (name, walk)), None)


def _claims(table: list[dict[str, Any]], maps: tuple[str, ...], walks: tuple[str, ...]) -> list[Claim]:
    claims = []
    for name in maps:
        base = _cell(table, name, "random")
        for walk in walks:
            e = _cell(table, name, walk)
            if walk == "random" or e is None or base is None:
                continue
            faster = e["t90_mean_s"] <= base["t90_mean_s"] / 3
            no_lower = e["coverage_mean"] >= base["coverage_mean"] - max(e["coverage_ci95"], base["coverage_ci95"])
            no_more = e["deployed_mean"] <= base["deployed_mean"] + max(e["deployed_ci95"], base["deployed_ci95"])
            connected = e["all_connected_runs"] == e["runs"]
            met = faster and no_lower and no_more and connected
            claims.append(Claim(
                f"{name}: {walk} spreads at least 3x faster than the random walk (the walk rules' goal)",
                "t90 <= random's / 3, coverage no lower, routers no more, all connected",
                f"t90 {e['t90_mean_s']:.0f} s vs {base['t90_mean_s']:.0f} s; to the random walk's level "
                f"{e['t_random_level_mean_s']:.0f} s vs {base['t_random_level_mean_s']:.0f} s; coverage "
                f"{100 * e['coverage_mean']:.1f} % vs {100 * base['coverage_mean']:.1f} %; routers "
                f"{e['deployed_mean']:.1f} vs {base['deployed_mean']:.1f}; connected in {e['all_connected_runs']}/"
                f"{e['runs']}",
                "holds" if met else "does not hold: " + ", ".join(
                    why for ok, why in ((faster, "not 3x faster"), (no_lower, "lower coverage"),
                                        (no_more, "more routers"), (connected, "a router cut off")) if not ok)))
    return claims


def _markdown(table: list[dict[str, Any]], claims: list[Claim], runs: int, time_limit: float) -> str:
    lines = ["# Walk rules of self-spreading", "",
             f"{runs} runs per map and rule (the same seeds), at most {time_limit:g} s. Mean ± 95 % CI; t90: time to "
             "90 % of the run's own final coverage; level: time to 90 % of the random walk's mean final coverage on "
             "the map (runs that never got there are left out of the mean and counted).", "",
             "| map | walk | final coverage | t90 (s) | to the random walk's level (s) | routers deployed "
             "| all connected | settled |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for e in table:
        never = f" ({e['t_random_level_never']} never)" if e["t_random_level_never"] else ""
        lines.append(f"| {e['map']} | {e['walk']} | "
                     f"{mean_ci_text(100 * e['coverage_mean'], 100 * e['coverage_ci95'])} % | "
                     f"{mean_ci_text(e['t90_mean_s'], e['t90_ci95_s'])} | "
                     f"{mean_ci_text(e['t_random_level_mean_s'], e['t_random_level_ci95_s'])}{never} | "
                     f"{mean_ci_text(e['deployed_mean'], e['deployed_ci95'])} | "
                     f"{e['all_connected_runs']}/{e['runs']} | {e['settled_runs']}/{e['runs']} |")
    return "\n".join(lines) + "\n\n" + claims_markdown("Do the local rules meet their goal?", claims)


def _figure(grid: np.ndarray, curves: dict[tuple[str, str], list[np.ndarray]], maps: tuple[str, ...],
            walks: tuple[str, ...]) -> bytes:
    """Mean coverage over time per walk rule, one panel per map, with 95 % bands."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3.4 * len(maps), 3.2))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(maps), squeeze=False)[0]
    for ax, name in zip(axes, maps, strict=True):
        for k, walk in enumerate(walks):
            runs = curves.get((name, walk))
            if not runs:
                continue
            arr = np.array(runs)
            mean = arr.mean(axis=0)
            half = 1.96 * arr.std(axis=0, ddof=1) / np.sqrt(len(arr)) if len(arr) > 1 else np.zeros_like(mean)
            ax.plot(grid, 100 * mean, color=f"C{k}", label=walk)
            ax.fill_between(grid, 100 * (mean - half), 100 * (mean + half), color=f"C{k}", alpha=0.2, lw=0)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("time (s)")
        ax.set_ylim(0, 102)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("coverage (%)")
    axes[0].legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
