"""Paper Fig. 7: routers needed vs number of base stations, for 1, 2 and 3 agents per base station.

``n`` = 1..4 base stations at the corners of ``office-32x32`` (in the order of the paper's Fig. 4), ``N_apbs`` =
1, 2, 3 agents per base station, a fixed ``r_c`` (default 6 m; the paper does not print its value), local
triangular rule, ``runs`` seeded runs per point. Each run stops at 99 % coverage; the count includes the base
reference nodes.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from amronet.experiments.common import (
    CORNERS,
    Claim,
    agent_scenario,
    claims_markdown,
    csv_text,
    load_plotting,
    write_outputs,
)
from amronet.experiments.options import AGENT_TIME_LIMIT_S, RunOptions
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_text

__all__ = ["run_fig7"]


def run_fig7(
    out_dir: Path,
    map_name: str = "office-32x32",
    r_c: float = 6.0,
    bases: tuple[int, ...] = (1, 2, 3, 4),
    agents: tuple[int, ...] = (1, 2, 3),
    runs: int = 5,
    options: RunOptions | None = None,
) -> dict[str, Any]:
    """Run the Fig. 7 experiment and write ``fig7_runs.csv``, ``fig7.png`` and ``fig7_claims.md`` to ``out_dir``.

    Args:
        out_dir: Output folder (replaced atomically; its result store is kept).
        map_name: The floor.
        r_c: Communication radius in metres.
        bases: The numbers of base stations ``n`` (at the corners, in the paper's order).
        agents: The numbers of agents per base station ``N_apbs``.
        runs: Seeded runs per point.
        options: How the runs are made (default :class:`RunOptions`): the agents' ``explorer``, ``time_limit``
            (default :data:`~amronet.experiments.options.AGENT_TIME_LIMIT_S`), and ``seed``: job ``k`` uses
            ``seed * 100000 + 50000 + k``; the others say where the runs execute (:func:`run_jobs`).

    Returns:
        ``{"rows": per-run rows, "table": per-(n, N_apbs) statistics, "claims": [Claim], "markdown": str}``.
    """
    options = options or RunOptions()
    time_limit = options.time_limit_or(AGENT_TIME_LIMIT_S)
    jobs = []
    for n in bases:
        for n_a in agents:
            for k in range(runs):
                labels = {"map": map_name, "r_c": float(r_c), "bases": n, "agents_per_base": n_a, "run": k}
                scenario = agent_scenario(map_name, r_c, CORNERS[:n], n_a, options.explorer, time_limit)
                jobs.append({"scenario": scenario, "seed": options.seed * 100_000 + 50_000 + len(jobs),
                             "labels": labels})
    results = run_jobs(jobs, options, description="fig7", meanwhile=load_plotting)
    rows = []
    for res in results:
        s = res["summary"]
        states = s["states"]
        rows.append({**res["labels"], "seed": res["seed"], "nodes_total": s["nodes_total"],
                     "triangle_routers": states.get("triangle-settled", 0) + states.get("triangle", 0),
                     "coverage": round(s["coverage"], 6), "stop_reason": s["stop_reason"],
                     "sim_time_s": s["sim_time_s"], "agents_connected_fraction": s["agents_connected_fraction"],
                     "wall_time_s": round(s["wall_time_s"], 3)})
    table = []
    for n in bases:
        for n_a in agents:
            sel = [r for r in rows if r["bases"] == n and r["agents_per_base"] == n_a]
            done = [r for r in sel if r["stop_reason"] == "coverage_target"]
            mean, half = mean_ci(np.array([r["nodes_total"] for r in done], dtype=float))
            table.append({"bases": n, "agents_per_base": n_a, "runs": len(sel), "completed": len(done),
                          "nodes_mean": mean, "nodes_ci95": half,
                          "triangle_mean": float(np.mean([r["triangle_routers"] for r in sel])) if sel else 0.0,
                          "connected_min": min((r["agents_connected_fraction"] for r in sel), default=float("nan"))})
    claims = _claims(table, agents)
    markdown = _markdown(table, claims, map_name, r_c)
    files = {"fig7_runs.csv": csv_text(rows), "fig7_table.csv": csv_text(table), "fig7_claims.md": markdown,
             "fig7.png": _figure(table, bases, agents, map_name, r_c)}
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "claims": claims, "markdown": markdown}


def _spread(values: list[float]) -> float:
    v = np.array([x for x in values if not np.isnan(x)])
    return float((v.max() - v.min()) / v.mean()) if len(v) > 1 else 0.0


def _markdown(table: list[dict[str, Any]], claims: list[Claim], map_name: str, r_c: float) -> str:
    """The Markdown table of routers needed (over the runs that reached the coverage target), and the claims."""
    lines = [f"# Fig. 7: routers needed vs base stations ({map_name}, r_c = {r_c:g} m)", "",
             "| base stations | agents per base | reached target | routers mean ± 95 % CI | triangle routers (mean) |",
             "|---:|---:|---:|---:|---:|"]
    lines += [f"| {e['bases']} | {e['agents_per_base']} | {e['completed']}/{e['runs']} | "
              f"{mean_ci_text(e['nodes_mean'], e['nodes_ci95'])} | {e['triangle_mean']:.1f} |" for e in table]
    return "\n".join(lines) + "\n\n" + claims_markdown("The paper's claims (5.1.2) and ours", claims)


def _claims(table: list[dict[str, Any]], agents: tuple[int, ...]) -> list[Claim]:
    by_n: dict[int, list[float]] = {}
    for e in table:
        by_n.setdefault(e["bases"], []).append(e["nodes_mean"])
    worst = max((_spread(v) for v in by_n.values()), default=0.0)
    claims = [Claim("More agents per base station do not change the routers needed (fixed n)", "independent",
                    f"largest spread across agents per base at one n: {100 * worst:.0f} % of the mean",
                    "reproduced" if worst <= 0.15 else "not reproduced")]
    for n_a in agents[:2]:
        means = [e["nodes_mean"] for e in table if e["agents_per_base"] == n_a]
        spread = _spread(means)
        claims.append(Claim(f"With {n_a} agent(s) per base the total is more or less the same for every n",
                            "more or less the same", f"spread across n: {100 * spread:.0f} % of the mean",
                            "reproduced" if spread <= 0.2 else "not reproduced"))
    conn = min(e["connected_min"] for e in table)
    claims.append(Claim("Agents never lose their connection", "never", f"mean connected fraction, worst run: "
                        f"{conn:.3f}", "reproduced" if conn == 1.0 else "not reproduced"))
    return claims


def _figure(table: list[dict[str, Any]], bases: tuple[int, ...], agents: tuple[int, ...], map_name: str,
            r_c: float) -> bytes:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 4.4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    for k, n_a in enumerate(agents):
        t = [e for e in table if e["agents_per_base"] == n_a]
        x = np.array([e["bases"] for e in t]) + (k - (len(agents) - 1) / 2) * 0.06
        ax.errorbar(x, [e["nodes_mean"] for e in t], yerr=[e["nodes_ci95"] for e in t], marker="o", capsize=3,
                    label=f"N_apbs = {n_a}")
    ax.set_xticks(list(bases))
    ax.set_xlabel("number of base stations n")
    ax.set_ylabel("routers incl. base nodes (mean, 95 % CI)")
    ax.set_title(f"Fig. 7 on {map_name}, r_c = {r_c:g} m")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    return buf.getvalue()
