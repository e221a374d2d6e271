"""Paper Figs. 10 and 11: coverage over time of self-spreading, DSSA and the potential field (paper 5.2.1).

Beyond the paper, the same runs of three location-aware Voronoi baselines are extra lines: VOR and Minimax (Wang,
Cao and La Porta) and Lloyd's algorithm (Cortés et al.); the paper's claims are judged on the paper's three only.

30 routers start at random in the 1 m x 1 m base region at the centre of a 6 m x 6 m field (``open-6x6`` for
Fig. 10, ``obstacles-6x6`` for Fig. 11), with the immobile reference node at the origin and ``r_c`` = 1 m. Run
``k`` of every algorithm uses the same seed, hence the same initial configuration: the comparison is paired.
As in the paper, forces from obstacles are added to DSSA and the potential field only in the obstacle
experiment (Fig. 11); walls still stop the robots in Fig. 10.

A run that settles (no router will move again) ends early; its last value holds for the rest of the horizon,
which is exact because nothing changes any more. Besides coverage (Eq. 1) we report *connected coverage*,
the area covered by nodes with a path to the base station, the part an agent can use.
"""

from __future__ import annotations

import io
from itertools import chain, repeat
from pathlib import Path
from typing import Any

import numpy as np

from amronet.experiments.common import Claim, claims_markdown, csv_table_text, csv_text, load_plotting, write_outputs
from amronet.experiments.options import RunOptions
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_columns, mean_ci_text

__all__ = ["ALGORITHMS", "BASELINES", "PAPER_ALGORITHMS", "run_coverage_over_time"]

PAPER_ALGORITHMS = ("self-spreading", "dssa", "potential-field")
"""The three algorithms of Figs. 10 and 11, in the paper's order of presentation."""
BASELINES = ("vor", "minimax", "lloyd")
"""The location-aware Voronoi baselines beyond the paper, drawn as extra (dashed) lines."""
ALGORITHMS = PAPER_ALGORITHMS + BASELINES
"""Every algorithm the figures compare by default: the paper's three first (they keep their colours)."""
MAPS = {"fig10": "open-6x6", "fig11": "obstacles-6x6"}
TIMESERIES_COLUMNS = ("algorithm", "run", "seed", "t", "coverage", "connected_coverage")
LABELS = {"self-spreading": "self-spreading", "dssa": "DSSA", "potential-field": "potential field (K = 1)",
          "vor": "VOR (location-aware)", "minimax": "Minimax (location-aware)", "lloyd": "Lloyd (location-aware)"}
DEFAULT_HORIZON_S = 900.0
"""Simulated seconds per run (the paper does not print its horizon; self-spreading has levelled off by then)."""
EARLY_S = 10.0
"""'Initially' in the paper's claim that self-spreading starts lower: the first ``EARLY_S`` seconds."""


def spreading_scenario(map_name: str, algorithm: str, obstacle_forces: bool, time_limit: float) -> dict[str, Any]:
    """The scenario of paper 5.2 for one algorithm, as plain data."""
    params: dict[str, Any] = {"triangular": "local"} if algorithm == "self-spreading" else {} \
        if algorithm in BASELINES else {"obstacle_forces": obstacle_forces}
    return {
        "name": f"{algorithm}-{map_name}",
        "map": map_name,
        "algorithm": {"name": algorithm, "params": params},
        "radio": {"model": "unit-disk", "r_c": 1.0},
        "base_stations": [{"x": 0.0, "y": 0.0, "region": [1.0, 1.0]}],
        "routers": {"count": 30, "robot": "bebot"},
        "sim": {"dt": 0.1, "time_limit": float(time_limit), "record_every": 10, "coverage_method": "raster"},
    }


def run_coverage_over_time(
    figure: str,
    out_dir: Path,
    runs: int = 50,
    algorithms: tuple[str, ...] | None = None,
    baseline_dir: Path | None = None,
    options: RunOptions | None = None,
) -> dict[str, Any]:
    """Run Fig. 10 or Fig. 11 and write its files to ``out_dir``.

    Files: ``FIG_timeseries.csv`` (every run's coverage over time), ``FIG_runs.csv`` (one row per run),
    ``FIG_table.csv``, ``FIG.png`` (mean and 95 % confidence band of coverage and connected coverage) and
    ``FIG_claims.md``.

    Args:
        figure: ``"fig10"`` (no obstacles) or ``"fig11"`` (obstacles).
        out_dir: Output folder (replaced atomically).
        runs: Runs per algorithm (the paper: 50).
        algorithms: Which algorithms to compare (default: the paper's three, :data:`PAPER_ALGORITHMS`, and with
            ``options.baselines`` the Voronoi baselines too, :data:`BASELINES`).
        baseline_dir: For Fig. 11, the folder of a Fig. 10 run to compare final coverage with (default: the
            sibling folder ``fig10`` of ``out_dir``, when it has a table).
        options: How the runs are made (default :class:`RunOptions`): ``time_limit``, the horizon in simulated
            seconds (default :data:`DEFAULT_HORIZON_S`, 900), and ``seed``: run ``k`` uses ``seed * 100000 + k``
            for every algorithm; the others say where the runs execute (:func:`run_jobs`). ``explorer`` is not
            used: these figures run no agents; ``baselines``: also the Voronoi baselines (when ``algorithms`` is not
            given).
    """
    if figure not in MAPS:
        raise ValueError(f"figure must be one of {sorted(MAPS)}, not {figure!r}")
    map_name = MAPS[figure]
    options = options or RunOptions()
    if algorithms is None:
        algorithms = ALGORITHMS if options.baselines else PAPER_ALGORITHMS
    time_limit = float(options.time_limit_or(DEFAULT_HORIZON_S))
    obstacles = figure == "fig11"
    jobs = []
    for algorithm in algorithms:
        scenario = spreading_scenario(map_name, algorithm, obstacles, time_limit)
        for k in range(runs):
            jobs.append({"scenario": scenario, "seed": options.seed * 100_000 + k, "timeseries": True,
                         "labels": {"figure": figure, "map": map_name, "algorithm": algorithm, "run": k}})
    results = run_jobs(jobs, options, description=figure, meanwhile=load_plotting)

    grid = np.arange(0.0, time_limit + 1e-9, 1.0)
    series: dict[str, dict[str, np.ndarray]] = {a: {"coverage": [], "connected_coverage": []} for a in algorithms}
    rows, ts_rows = [], []
    for res in results:
        lab, s, ts = res["labels"], res["summary"], res["timeseries"]
        t = np.asarray(ts["t"], dtype=float)
        for col in ("coverage", "connected_coverage"):
            series[lab["algorithm"]][col].append(_hold(t, np.asarray(ts[col], dtype=float), grid))
        cov = np.asarray(ts["coverage"], dtype=float)
        rows.append({**lab, "seed": res["seed"], "coverage": round(s["coverage"], 6),
                     "connected_coverage": round(s["connected_coverage"], 6),
                     "coverage_at_early": round(float(_hold(t, cov, np.array([EARLY_S]))[0]), 6),
                     "time_to_90pct_s": _time_to_fraction(t, cov, 0.9),
                     "distance_per_router_m": round(s["mean_distance_per_router_m"], 4),
                     "routers_connected_fraction": round(s["routers_connected_fraction"], 4),
                     "components": s["components"], "settled_at_s": s["settled_at_s"],
                     "stop_reason": s["stop_reason"], "wall_time_s": round(s["wall_time_s"], 3)})
        n = len(t)
        ts_rows.append(zip(repeat(lab["algorithm"], n), repeat(lab["run"], n), repeat(res["seed"], n), t.tolist(),
                           [round(float(c), 6) for c in ts["coverage"]],
                           [round(float(c), 6) for c in ts["connected_coverage"]], strict=True))
    curves = {a: {col: np.array(v) for col, v in d.items()} for a, d in series.items()}
    table = [{**_table_row(a, [r for r in rows if r["algorithm"] == a]), "horizon_s": time_limit} for a in algorithms]
    baseline, why_not = None, ""
    if obstacles:
        folder = baseline_dir if baseline_dir is not None else Path(out_dir).parent / "fig10"
        baseline, why_not = _load_baseline(folder, runs, time_limit)
    claims = _claims(figure, [e for e in table if e["algorithm"] in PAPER_ALGORITHMS], baseline, why_not)
    markdown = _markdown(figure, map_name, runs, time_limit, table, claims)
    files = {f"{figure}_timeseries.csv": csv_table_text(TIMESERIES_COLUMNS, chain.from_iterable(ts_rows)),
             f"{figure}_runs.csv": csv_text(rows),
             f"{figure}_table.csv": csv_text(table), f"{figure}_claims.md": markdown,
             f"{figure}.png": _figure(figure, map_name, grid, curves, runs)}
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "claims": claims, "markdown": markdown, "curves": curves, "grid": grid}


def _hold(t: np.ndarray, values: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Values on ``grid``: the last recorded value at or before each instant (held after the run ended)."""
    idx = np.searchsorted(t, grid + 1e-9, side="right") - 1
    return values[np.clip(idx, 0, len(values) - 1)]


def _time_to_fraction(t: np.ndarray, values: np.ndarray, fraction: float) -> float:
    """First recorded time at which ``values`` reach ``fraction`` of their final value."""
    reached = np.flatnonzero(values >= fraction * values[-1] - 1e-12)
    return float(t[reached[0]]) if len(reached) else float("nan")


def _table_row(algorithm: str, rows: list[dict[str, Any]]) -> dict[str, Any]:
    def stat(key: str) -> tuple[float, float]:
        return mean_ci(np.array([np.nan if r[key] is None else r[key] for r in rows], dtype=float))

    cov, cov_h = stat("coverage")
    con, con_h = stat("connected_coverage")
    early, early_h = stat("coverage_at_early")
    t90, t90_h = stat("time_to_90pct_s")
    dist, dist_h = stat("distance_per_router_m")
    linked, linked_h = stat("routers_connected_fraction")
    settled = [r["settled_at_s"] for r in rows if r["settled_at_s"] is not None]
    return {"algorithm": algorithm, "runs": len(rows),
            "coverage_mean": cov, "coverage_ci95": cov_h,
            "connected_coverage_mean": con, "connected_coverage_ci95": con_h,
            "coverage_early_mean": early, "coverage_early_ci95": early_h,
            "time_to_90pct_mean_s": t90, "time_to_90pct_ci95_s": t90_h,
            "distance_per_router_mean_m": dist, "distance_per_router_ci95_m": dist_h,
            "routers_connected_mean": linked, "routers_connected_ci95": linked_h,
            # every router has a path to the base: counted over all routers, moving or not, because a moving
            # force-based router is as much a relay as a resting one (``components`` counts deployed nodes only)
            "runs_all_connected": sum(1 for r in rows if r["routers_connected_fraction"] == 1.0),
            "runs_converged": len(settled),
            "converged_at_median_s": float(np.median(settled)) if settled else float("nan")}


def _load_baseline(folder: Path, runs: int, horizon: float) -> tuple[dict[str, dict[str, float]] | None, str]:
    """The Fig. 10 table in ``folder`` if it was made with the same runs and horizon, else why not."""
    import csv

    path = Path(folder) / "fig10_table.csv"
    if not path.is_file():
        return None, f"no Fig. 10 table in {folder}"
    with path.open() as fh:
        table = {r["algorithm"]: {k: float(v) for k, v in r.items() if k != "algorithm"} for r in csv.DictReader(fh)}
    for row in table.values():
        if row.get("runs") != runs or row.get("horizon_s") != horizon:
            return None, (f"the Fig. 10 table in {folder} has {row.get('runs', 0):g} runs over "
                          f"{row.get('horizon_s', float('nan')):g} s, this run {runs} over {horizon:g} s")
    return table, ""


def _pp(x: float) -> str:
    return f"{100 * x:.1f} %"


def _pp_ci(mean: float, half: float) -> str:
    """A fraction's mean ± 95 % CI half-width in percent, both to the half-width's second significant digit."""
    return f"{mean_ci_text(100 * mean, 100 * half)} %"


SAME_POINTS = 0.02
"""'Almost the same' final coverage: within two percentage points (and confidently so)."""
SLIGHTLY_POINTS = 0.10
"""'Slightly lower': lower by at most ten percentage points."""


def _claims(figure: str, table: list[dict[str, Any]], baseline: dict[str, dict[str, float]] | None,
            why_not: str = "") -> list[Claim]:
    by = {e["algorithm"]: e for e in table}
    ss = by.get("self-spreading")
    others = [e for e in table if e["algorithm"] != "self-spreading"]
    claims: list[Claim] = []
    if ss is None or not others:
        return claims
    for key, what in (("coverage", "coverage"), ("connected_coverage", "connected coverage")):
        beaten = [e for e in others if ss[f"{key}_mean"] - ss[f"{key}_ci95"] > e[f"{key}_mean"] + e[f"{key}_ci95"]]
        ours = "; ".join(f"{LABELS[e['algorithm']]} {_pp_ci(e[f'{key}_mean'], e[f'{key}_ci95'])}"
                         for e in others)
        claims.append(Claim(f"Self-spreading ends with more {what} than the force-based algorithms",
                            "higher" if key == "coverage" else "(not in the paper)",
                            f"self-spreading {_pp_ci(ss[f'{key}_mean'], ss[f'{key}_ci95'])}; {ours}",
                            _verdict(len(beaten) == len(others), len(beaten) > 0) if key == "coverage" else
                            ("holds" if len(beaten) == len(others) else "holds partly" if beaten else "does not hold")))
    gaps = [e["coverage_early_mean"] - ss["coverage_early_mean"] for e in others]
    lower = all(g > 0 for g in gaps)
    slightly = lower and max(gaps) <= SLIGHTLY_POINTS
    claims.append(Claim(f"Initially (t = {EARLY_S:g} s) self-spreading covers slightly less",
                        "slightly lower",
                        f"self-spreading {_pp(ss['coverage_early_mean'])}; "
                        + "; ".join(f"{LABELS[e['algorithm']]} {_pp(e['coverage_early_mean'])}" for e in others),
                        "reproduced" if slightly else "partly (lower, but by far more than slightly)" if lower
                        else "not reproduced"))
    if figure == "fig11":
        if baseline is None:
            claims.append(Claim("Force-based algorithms degrade with obstacles, self-spreading does not",
                                "degrade / almost the same", why_not,
                                "not evaluated (run fig10 with the same runs and horizon first)"))
        else:
            drops = {e["algorithm"]: baseline[e["algorithm"]]["coverage_mean"] - e["coverage_mean"]
                     for e in table if e["algorithm"] in baseline}
            halfs = {e["algorithm"]: baseline[e["algorithm"]]["coverage_ci95"] + e["coverage_ci95"]
                     for e in table if e["algorithm"] in baseline}
            ss_drop, ss_half = abs(drops.get("self-spreading", np.nan)), halfs.get("self-spreading", np.nan)
            ss_same = ss_drop + ss_half <= SAME_POINTS  # the whole confidence range within two points
            degraded = [a for a in drops if a != "self-spreading" and drops[a] > halfs[a]
                        and drops[a] > drops.get("self-spreading", 0.0)]
            ours = "; ".join(f"{LABELS[a]} {'-' if d >= 0 else '+'}{_pp(abs(d))}" for a, d in drops.items())
            claims.append(Claim("Self-spreading's final coverage is almost the same with obstacles",
                                "almost the same", f"change from Fig. 10: {ours}",
                                "reproduced" if ss_same else "inconclusive (confidence intervals too wide)"
                                if ss_drop <= SAME_POINTS else "not reproduced"))
            n_force = len([a for a in drops if a != "self-spreading"])
            claims.append(Claim("DSSA and the potential field degrade with obstacles (more than self-spreading)",
                                "degrade", f"significant drops larger than self-spreading's: "
                                f"{', '.join(LABELS[a] for a in degraded) or 'none'}",
                                _verdict(len(degraded) == n_force, len(degraded) > 0)))
    return claims


def _verdict(all_: bool, some: bool) -> str:
    return "reproduced" if all_ else ("partly" if some else "not reproduced")


def _markdown(figure: str, map_name: str, runs: int, horizon: float, table: list[dict[str, Any]],
              claims: list[Claim]) -> str:
    number = figure[3:]
    lines = [f"# Fig. {number}: coverage over time on {map_name} ({runs} runs per algorithm, {horizon:g} s)", "",
             "| algorithm | final coverage | final connected coverage | coverage at "
             f"{EARLY_S:g} s | time to 90 % of final (s) | distance per router (m) | routers connected to base "
             "| runs with every router connected | runs converged (median time) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for e in table:
        conv = (f"{e['runs_converged']}/{e['runs']} ({e['converged_at_median_s']:.0f} s)" if e["runs_converged"]
                else f"0/{e['runs']}")
        lines.append(
            f"| {LABELS[e['algorithm']]} | {_pp_ci(e['coverage_mean'], e['coverage_ci95'])} | "
            f"{_pp_ci(e['connected_coverage_mean'], e['connected_coverage_ci95'])} | "
            f"{_pp(e['coverage_early_mean'])} | {mean_ci_text(e['time_to_90pct_mean_s'], e['time_to_90pct_ci95_s'])} | "
            f"{e['distance_per_router_mean_m']:.2f} | {_pp(e['routers_connected_mean'])} | "
            f"{e['runs_all_connected']}/{e['runs']} | {conv} |")
    return "\n".join(lines) + "\n\n" + claims_markdown(f"The paper's claims (5.2.1, Fig. {number}) and ours", claims)


def _figure(figure: str, map_name: str, grid: np.ndarray, curves: dict[str, dict[str, np.ndarray]],
            runs: int) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 4.2))
    FigureCanvasAgg(fig)
    panels = (("coverage", "coverage (Eq. 1)"), ("connected_coverage", "connected coverage"))
    for k, (col, label) in enumerate(panels):
        ax = fig.add_subplot(1, 2, k + 1)
        for algorithm, d in curves.items():
            if len(d[col]) == 0:
                continue
            mean, half = mean_ci_columns(d[col])
            (line,) = ax.plot(grid, 100 * mean, label=LABELS[algorithm],
                              linestyle="--" if algorithm in BASELINES else "-")
            ax.fill_between(grid, 100 * (mean - half), 100 * (mean + half), color=line.get_color(), alpha=0.25,
                            linewidth=0)
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"{label} (%)")
        ax.set_ylim(0, 100)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="lower right", fontsize="small")
    fig.suptitle(f"Fig. {figure[3:]}: {map_name}, 30 routers, r_c = 1 m, mean and 95 % CI of {runs} runs")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
