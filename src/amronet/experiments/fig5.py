"""Paper Fig. 5: routers needed vs communication radius, agent-assisted deployment against static patterns.

``r_c`` = 4..10 m on a 32 m x 32 m floor (``office-32x32`` and ``open-32x32``), one base station; ``N_a`` = 1..4
agents, each with 5 start locations (the four corners and the centre), so 20 runs per radius and map. Each
run stops when 99 % of the reachable free space is covered; the count includes the base reference node. Beside
it: the placed (minimum) and estimated counts of the four static patterns on the same area, and the planning
estimate 0.77 A / r^2 the paper proposes (section 6.1). With ``options.optimum`` the table gains the optimum and
each count's ratio to it (:mod:`~amronet.experiments.fig5_optimum`).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from amronet.experiments.common import (
    START_LOCATIONS,
    Claim,
    agent_scenario,
    claims_markdown,
    csv_text,
    load_plotting,
    write_outputs,
)
from amronet.experiments.options import AGENT_TIME_LIMIT_S, RunOptions
from amronet.experiments.runner import run_jobs
from amronet.patterns import estimate, place
from amronet.sweeps.stats import mean_ci, mean_ci_text

__all__ = ["PATTERNS", "run_fig5"]

PATTERNS = ("r-strip", "hexagonal", "square", "triangular")
SHORT = {"r-strip": "RSTR", "hexagonal": "HEX", "square": "SQR", "triangular": "TRI"}
"""A pattern's column title in the tables."""
AREA = (32.0, 32.0)


def _pattern_counts(radii: list[float]) -> dict[str, dict[float, dict[str, float]]]:

    out: dict[str, dict[float, dict[str, float]]] = {}
    for name in PATTERNS:
        out[name] = {}
        for r in radii:
            placement = place(name, AREA, r)
            out[name][r] = {"placed": placement.count, "estimated": estimate(name, AREA[0] * AREA[1], r),
                            "coverage": placement.coverage}
    return out


def run_fig5(
    out_dir: Path,
    maps: tuple[str, ...] = ("office-32x32", "open-32x32"),
    radii: tuple[float, ...] = (4, 5, 6, 7, 8, 9, 10),
    agents: tuple[int, ...] = (1, 2, 3, 4),
    starts: int = 5,
    options: RunOptions | None = None,
    optimum_spacing: float | None = None,
) -> dict[str, Any]:
    """Run the Fig. 5 experiment and write ``fig5_runs.csv``, ``fig5.png`` and ``fig5_claims.md`` to ``out_dir``.

    Args:
        out_dir: Output folder (replaced atomically; its result store is kept).
        maps: The floors.
        radii: The communication radii ``r_c`` in metres.
        agents: The numbers of agents ``N_a``.
        starts: How many of the five start locations (corners, then the centre).
        options: How the runs are made (default :class:`RunOptions`): the agents' ``explorer``, ``time_limit``
            (default :data:`~amronet.experiments.options.AGENT_TIME_LIMIT_S`), and ``seed``: job ``k`` uses
            ``seed * 100000 + k``; ``optimum``: also the optimum per map and radius, searched for that many
            seconds each and kept in ``store`` (:func:`~amronet.experiments.fig5_optimum.solve_optima`), before the
            runs; the others say where the runs execute (:func:`run_jobs`).
        optimum_spacing: The optimum's candidate spacing (m); ``None``: ``options.optimum_spacing``, or ``r_c / 2``.

    Returns:
        ``{"rows": per-run rows, "table": per-(map, r_c) statistics, "claims": [Claim], "markdown": str}``.
    """
    options = options or RunOptions()
    time_limit = options.time_limit_or(AGENT_TIME_LIMIT_S)
    optima = None
    if options.optimum is not None:  # before the runs: bad input fails at once, and a rerun loads them
        from amronet.experiments.fig5_optimum import solve_optima

        spacing = optimum_spacing if optimum_spacing is not None else options.optimum_spacing
        optima = solve_optima(maps, [float(r) for r in radii], options.optimum, spacing, options.store,
                              options.show_progress)
    jobs = []
    for map_name in maps:
        for r in radii:
            for n_a in agents:
                for s, loc in enumerate(START_LOCATIONS[:starts]):
                    labels = {"map": map_name, "r_c": float(r), "agents": n_a, "start": s}
                    scenario = agent_scenario(map_name, r, (loc,), n_a, options.explorer, time_limit)
                    jobs.append({"scenario": scenario, "seed": options.seed * 100_000 + len(jobs), "labels": labels})
    patterns: dict[str, dict[float, dict[str, float]]] = {}

    def meanwhile() -> None:  # while the workers run
        patterns.update(_pattern_counts([float(r) for r in radii]))
        load_plotting()

    results = run_jobs(jobs, options, description="fig5", meanwhile=meanwhile)
    rows = []
    for res in results:
        s = res["summary"]
        rows.append({**res["labels"], "seed": res["seed"], "nodes_total": s["nodes_total"],
                     "routers_deployed": s["routers_deployed"], "coverage": round(s["coverage"], 6),
                     "stop_reason": s["stop_reason"], "sim_time_s": s["sim_time_s"],
                     "agents_connected_fraction": s["agents_connected_fraction"],
                     "reachable_area_m2": round(s["reachable_area_m2"], 3), "wall_time_s": round(s["wall_time_s"], 3)})
    table = []
    for map_name in maps:
        for r in radii:
            sel = [row for row in rows if row["map"] == map_name and row["r_c"] == float(r)]
            nodes = np.array([row["nodes_total"] for row in sel], dtype=float)
            done = np.array([row["stop_reason"] == "coverage_target" for row in sel])
            mean, half = mean_ci(nodes[done]) if done.any() else (float("nan"), float("nan"))
            area = sel[0]["reachable_area_m2"] if sel else float("nan")
            entry = {"map": map_name, "r_c": float(r), "runs": len(sel), "completed": int(done.sum()),
                     "ard_mean": mean, "ard_ci95": half, "ard_est_077": 0.77 * area / r**2,
                     "connected_min": min((row["agents_connected_fraction"] for row in sel), default=float("nan"))}
            for name in PATTERNS:
                entry[f"{name}_placed"] = patterns[name][float(r)]["placed"]
                entry[f"{name}_estimated"] = patterns[name][float(r)]["estimated"]
            table.append(entry)
    claims = _claims(table)
    markdown = _markdown(table, claims)
    if optima is not None:
        from amronet.experiments.fig5_optimum import add_optimum, optimum_markdown

        add_optimum(table, optima, PATTERNS)
        markdown += "\n" + optimum_markdown(table, PATTERNS, SHORT)
    files = {"fig5_runs.csv": csv_text(rows), "fig5_table.csv": csv_text(table), "fig5_claims.md": markdown,
             "fig5.png": _figure(table, maps)}
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "claims": claims, "markdown": markdown}


def _claims(table: list[dict[str, Any]]) -> list[Claim]:
    claims = []
    for map_name in sorted({t["map"] for t in table}):
        t = [e for e in table if e["map"] == map_name and not np.isnan(e["ard_mean"])]
        if not t:
            continue
        wins = {p: sum(e["ard_mean"] < e[f"{p}_placed"] for e in t) for p in ("hexagonal", "square", "triangular")}
        beats = sum(all(e["ard_mean"] < e[f"{p}_placed"] for p in wins) for e in t)
        ours = ", ".join(f"{p} {wins[p]}/{len(t)}" for p in wins)
        claims.append(Claim(f"[{map_name}] ARD needs fewer routers than the placed hexagonal, square and "
                            "triangular grids", "yes, at every r_c (Fig. 5)",
                            f"fewer than all three at {beats} of {len(t)} radii; per grid: {ours}",
                            "reproduced" if beats == len(t) else ("partly" if any(wins.values()) else
                                                                  "not reproduced")))
        rel = [(e["ard_mean"] - e["r-strip_placed"]) / e["r-strip_placed"] for e in t]
        claims.append(Claim(f"[{map_name}] ARD is close to the placed r-strip (RSTR_min)", "close",
                            f"ARD - RSTR_min: {100 * np.mean(rel):+.0f} % on average "
                            f"({100 * min(rel):+.0f} % to {100 * max(rel):+.0f} %)",
                            "reproduced" if abs(np.mean(rel)) <= 0.25 else "not reproduced"))
        err = [(e["ard_est_077"] - e["ard_mean"]) / e["ard_mean"] for e in t]
        claims.append(Claim(f"[{map_name}] 0.77 A / r^2 estimates ARD's count (for planning)", "very close",
                            f"estimate - ARD: {100 * np.mean(err):+.0f} % on average "
                            f"({100 * min(err):+.0f} % to {100 * max(err):+.0f} %)",
                            "reproduced" if abs(np.mean(err)) <= 0.2 else "not reproduced"))
        conn = min(e["connected_min"] for e in t)
        claims.append(Claim(f"[{map_name}] agents never lose their connection", "never",
                            f"mean connected fraction, worst run: {conn:.3f}",
                            "reproduced" if conn == 1.0 else "not reproduced"))
    return claims


def _markdown(table: list[dict[str, Any]], claims: list[Claim]) -> str:
    lines = ["# Fig. 5: routers needed vs r_c (agent-assisted deployment vs static patterns)", "",
             "| map | r_c | reached target | ARD mean ± 95 % CI | 0.77 A/r² | RSTR min/est | HEX min/est | "
             "SQR min/est | TRI min/est |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for e in table:
        lines.append(
            f"| {e['map']} | {e['r_c']:g} | {e['completed']}/{e['runs']} | "
            f"{mean_ci_text(e['ard_mean'], e['ard_ci95'])} | {e['ard_est_077']:.1f} | "
            f"{e['r-strip_placed']}/{e['r-strip_estimated']} | "
            f"{e['hexagonal_placed']}/{e['hexagonal_estimated']} | {e['square_placed']}/{e['square_estimated']} | "
            f"{e['triangular_placed']}/{e['triangular_estimated']} |")
    return "\n".join(lines) + "\n\n" + claims_markdown("The paper's claims (5.1.1, 6.1) and ours", claims)


def _figure(table: list[dict[str, Any]], maps: tuple[str, ...]) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0 * len(maps), 4.6))
    FigureCanvasAgg(fig)
    styles = {"r-strip": ("C1", "o"), "hexagonal": ("C2", "s"), "square": ("C3", "^"), "triangular": ("C4", "v")}
    for k, map_name in enumerate(maps):
        ax = fig.add_subplot(1, len(maps), k + 1)
        t = [e for e in table if e["map"] == map_name]
        r = np.array([e["r_c"] for e in t])
        mean = np.array([e["ard_mean"] for e in t])
        half = np.array([e["ard_ci95"] for e in t])
        ax.errorbar(r, mean, yerr=half, color="C0", marker="D", capsize=3, lw=2, label="ARD (mean, 95 % CI)")
        ax.plot(r, [e["ard_est_077"] for e in t], color="C0", ls=":", label="0.77 A / r² (planning estimate)")
        if t and "opt_best_nodes" in t[0]:  # reproduce fig5 --optimum
            best = [e["opt_best_nodes"] for e in t]
            ax.fill_between(r, [e["opt_bound_nodes"] for e in t], best, color="0.5", alpha=0.25, lw=0,
                            label="optimum: proven bound to best")
            ax.plot(r, best, color="k", marker="x", ms=5, lw=1.2, label="optimum on a lattice (best found)")
        for name, (colour, marker) in styles.items():
            ax.plot(r, [e[f"{name}_placed"] for e in t], color=colour, marker=marker, ms=4, label=f"{name} placed")
            ax.plot(r, [e[f"{name}_estimated"] for e in t], color=colour, ls="--", lw=0.8,
                    label=f"{name} estimated")
        ax.set_xlabel("communication radius r_c [m]")
        ax.set_ylabel("routers incl. base node")
        ax.set_title(f"Fig. 5 on {map_name}")
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)
        if k == len(maps) - 1:
            ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    return buf.getvalue()
