"""``amronet reproduce buildings``: which drop rule keeps agents connected in a real building, and at what cost.

Agent-assisted deployment with 3 agents from one base station on five floor plans (``office-32x32`` and four real
maps), for every drop rule (:mod:`amronet.algorithms.agent_assisted.drops`) × radio (the paper's unit disk, and
``multi-wall`` with
4 dB of correlated shadowing) × stock per agent (unlimited, 12, 6; an agent whose stock runs out goes on and may be
cut off, ``agents.when_empty: continue``, so that the cost of a short stock shows as outages). Each run stops at 99 %
coverage or after ``time_limit`` (default 600 s). Per cell: the relays used and the fraction of time the agents were
connected to a base station (mean and 95 % CI), how many runs had an outage, the longest outage, coverage.

The base stations sit at free points chosen for each map (:data:`BUILDINGS`, with the communication radius that
suits its size); the static r-strip pattern placed on the free space the base reaches is the count
``strip-goals`` is compared with (paper section 6). With ``options.optimum`` the table gains the optimum per
building and radio and each cell's ratio to it (:mod:`~amronet.experiments.buildings_optimum`).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from amronet.experiments.building_cells import BUILDINGS, RADIOS, RULES, STOCKS, TIME_LIMIT_S, Building
from amronet.experiments.common import Claim, agent_scenario, claims_markdown, csv_text, write_outputs
from amronet.experiments.options import RunOptions, check_optimum_options
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_text

__all__ = ["BUILDINGS", "RADIOS", "RULES", "STOCKS", "Building", "run_buildings"]

def _rules() -> dict[str, tuple[str, dict[str, Any]]]:
    """:data:`RULES`, and ``strip-goals`` when it is registered."""
    from amronet.algorithms.agent_assisted.drops import DROP_RULES

    return {**RULES, **({"strip-goals": ("strip-goals", {})} if "strip-goals" in DROP_RULES else {})}


def _cell_indices(rules: tuple[str, ...]) -> dict[tuple[str, str, str, int | None], int]:
    """Every cell of the full experiment → its place, which fixes its runs' seeds whatever subset runs.

    The cells of :data:`RULES` come first, building by building (the order of the first 3 000 runs, whose seeds
    the README's table was made with), then those of any further rule (``strip-goals``).
    """
    groups = (tuple(r for r in rules if r in RULES), tuple(r for r in rules if r not in RULES))
    order = [(b, r, radio, stock) for group in groups for b in BUILDINGS for r in group for radio in RADIOS
             for stock in STOCKS]
    return {cell: k for k, cell in enumerate(order)}


def run_buildings(
    out_dir: Path,
    buildings: tuple[str, ...] = tuple(BUILDINGS),
    rules: tuple[str, ...] | None = None,
    radios: tuple[str, ...] = tuple(RADIOS),
    stocks: tuple[int | None, ...] = STOCKS,
    runs: int = 20,
    options: RunOptions | None = None,
) -> dict[str, Any]:
    """Run the experiment; write ``buildings_runs.csv``, ``buildings_table.csv``, ``buildings.md``, ``buildings.png``.

    Args:
        out_dir: Output folder (replaced atomically; its result store is kept).
        buildings: Maps of :data:`BUILDINGS`.
        rules: Labels of the drop rules (default: all, :data:`RULES` and ``strip-goals``).
        radios: Labels of :data:`RADIOS`.
        stocks: Routers per agent (``None``: unlimited).
        runs: Seeded runs per cell.
        options: How the runs are made (default :class:`RunOptions`): the agents' ``explorer``, ``time_limit``
            (default 600 s) and ``seed``: run ``k`` of cell ``c`` uses ``seed * 100000 + 70000 + c * runs + k``,
            ``c`` the cell's place in the full experiment (:func:`_cell_indices`), so that a subset runs what the
            full experiment would; ``optimum``: also the optimum per building and radio, searched for that many
            seconds each on a lattice of ``optimum_spacing`` (default ``r_c / 2``) and kept in ``store``
            (:func:`~amronet.experiments.buildings_optimum.solve_building_optima`), before the runs; the others
            say where the runs execute (:func:`run_jobs`).

    Returns:
        ``{"rows", "table", "claims", "markdown"}``.

    Raises:
        AmronetError: A bad ``optimum`` or ``optimum_spacing`` (one line), before any run.
    """
    options = options or RunOptions()
    check_optimum_options(options.optimum, options.optimum_spacing)
    optima = None
    if options.optimum is not None:  # before the runs: bad input fails at once, and a rerun loads them
        from amronet.experiments.buildings_optimum import solve_building_optima

        optima = solve_building_optima(buildings, radios, options.optimum, options.optimum_spacing, options.store,
                                       options.show_progress)
    known = _rules()
    rules = tuple(known) if rules is None else rules
    time_limit = options.time_limit_or(TIME_LIMIT_S)
    cell_index = _cell_indices(tuple(known))
    jobs = []
    for name in buildings:
        b = BUILDINGS[name]
        for rule_label in rules:
            rule, drop = known[rule_label]
            for radio_label in radios:
                for stock in stocks:
                    agents = {} if stock is None else {"routers_carried": stock, "when_empty": "continue"}
                    scenario = agent_scenario(b.map, b.r_c, (b.base,), 3, options.explorer, time_limit,
                                              radio=RADIOS[radio_label], drop_rule=rule, drop=drop, agents=agents)
                    for k in range(runs):
                        labels = {"map": name, "rule": rule_label, "radio": radio_label,
                                  "stock": "unlimited" if stock is None else stock, "run": k}
                        cell = cell_index.setdefault((name, rule_label, radio_label, stock), len(cell_index))
                        jobs.append({"scenario": scenario, "seed": options.seed * 100_000 + 70_000 + cell * runs + k,
                                     "labels": labels})
    results = run_jobs(jobs, options, description="buildings")
    rows = [_row(res) for res in results]
    table = _table(rows)
    strips = _strip_counts(buildings)
    claims = _claims(table, strips)
    markdown = _markdown(table, strips, claims, runs, time_limit, options.explorer)
    if optima is not None:
        from amronet.experiments.buildings_optimum import add_building_optimum, building_optimum_markdown

        add_building_optimum(table, optima)
        markdown += "\n" + building_optimum_markdown(table, strips)
    files = {"buildings_runs.csv": csv_text(rows), "buildings_table.csv": csv_text(table),
             "buildings.md": markdown, "buildings.png": _figure(table, buildings, radios)}
    write_outputs(out_dir, files)
    return {"rows": rows, "table": table, "claims": claims, "markdown": markdown}


def _row(res: dict[str, Any]) -> dict[str, Any]:
    s = res["summary"]
    m = s["mission"]
    return {**res["labels"], "seed": res["seed"], "relays_used": m["relays_used"],
            "connected_fraction": round(m["connected_fraction"], 6), "outages": m["outages"],
            "longest_outage_s": m["longest_outage_s"], "coverage": round(s["coverage"], 6),
            "connected_coverage": round(s["connected_coverage"], 6),
            "relays_per_100m2_covered": m["relays_per_100m2_covered"], "stop_reason": s["stop_reason"],
            "sim_time_s": s["sim_time_s"], "wall_time_s": round(s["wall_time_s"], 3)}


def _table(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One entry per (map, rule, radio, stock): means with 95 % CIs."""
    cells: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        cells.setdefault((r["map"], r["rule"], r["radio"], r["stock"]), []).append(r)
    table = []
    for (name, rule, radio, stock), sel in cells.items():
        relays, relays_ci = mean_ci(np.array([r["relays_used"] for r in sel], dtype=float))
        conn, conn_ci = mean_ci(np.array([r["connected_fraction"] for r in sel], dtype=float))
        cov, cov_ci = mean_ci(np.array([r["coverage"] for r in sel], dtype=float))
        table.append({"map": name, "rule": rule, "radio": radio, "stock": stock, "runs": len(sel),
                      "relays_mean": relays, "relays_ci95": relays_ci, "connected_mean": conn,
                      "connected_ci95": conn_ci, "runs_cut_off": sum(r["outages"] > 0 for r in sel),
                      "longest_outage_s": max(r["longest_outage_s"] for r in sel), "coverage_mean": cov,
                      "coverage_ci95": cov_ci,
                      "reached_target": sum(r["stop_reason"] == "coverage_target" for r in sel)})
    return table


def _strip_counts(buildings: tuple[str, ...]) -> dict[str, int]:
    """Routers (nodes less the base node) of the static r-strip placed on the free space each base reaches."""
    from amronet.patterns import as_area, place
    from amronet.world import reachable_free, resolve_map

    out = {}
    for name in buildings:
        b = BUILDINGS[name]
        omap = resolve_map(b.map)
        mask = reachable_free(omap, np.array([b.base]))
        out[name] = int(place("r-strip", as_area(omap, mask=mask, r=b.r_c), b.r_c).count) - 1
    return out


def _cell(table: list[dict[str, Any]], name: str, rule: str, radio: str, stock: Any = "unlimited"
          ) -> dict[str, Any] | None:
    return next((e for e in table if (e["map"], e["rule"], e["radio"], e["stock"]) == (name, rule, radio, stock)),
                None)


def _best(table: list[dict[str, Any]], name: str, radio: str, stock: Any) -> dict[str, Any] | None:
    """The rule that kept agents connected longest (ties within 0.005: fewer relays)."""
    sel = [e for e in table if (e["map"], e["radio"], e["stock"]) == (name, radio, stock)]
    if not sel:
        return None
    top = max(e["connected_mean"] for e in sel)
    return min((e for e in sel if e["connected_mean"] >= top - 0.005), key=lambda e: e["relays_mean"])


def _claims(table: list[dict[str, Any]], strips: dict[str, int]) -> list[Claim]:
    claims = []
    for name in strips:
        paper = _cell(table, name, "last-reference", "multi-wall")
        if paper is not None:
            claims.append(Claim(f"{name}: the paper's distance rule keeps agents connected under walls",
                                "never cut off (unit disk)",
                                f"cut off in {paper['runs_cut_off']}/{paper['runs']} runs, connected "
                                f"{100 * paper['connected_mean']:.0f} % of the time",
                                "holds" if paper["runs_cut_off"] == 0 else "does not hold"))
        greedy = _cell(table, name, "last-reference", "unit-disk")
        lq, lq_walls = _cell(table, name, "link-quality", "unit-disk"), _cell(table, name, "link-quality", "multi-wall")
        if greedy is not None and lq is not None and lq_walls is not None:
            claims.append(Claim(f"{name}: what the link-quality rule costs (unlimited stock)",
                                "location-free greedy deployment (paper 6)",
                                f"unit disk {lq['relays_mean']:.1f} relays against the paper's "
                                f"{greedy['relays_mean']:.1f}; under walls {lq_walls['relays_mean']:.1f} relays, "
                                f"connected {100 * lq_walls['connected_mean']:.0f} % of the time",
                                "matches the paper's count" if lq["relays_mean"] <= greedy["relays_mean"]
                                + max(lq["relays_ci95"], greedy["relays_ci95"]) else "costs more relays"))
        strip = _cell(table, name, "strip-goals", "unit-disk")
        if strip is not None and greedy is not None:
            closer = abs(strip["relays_mean"] - strips[name]) < abs(greedy["relays_mean"] - strips[name])
            verdict = "holds" if strip["relays_mean"] > strips[name] else "does not hold"
            claims.append(Claim(f"{name}: strip goals do not reach the static r-strip count (paper 6)",
                                "they cannot", f"strip-goals {strip['relays_mean']:.1f}, greedy "
                                f"{greedy['relays_mean']:.1f}, static r-strip {strips[name]}",
                                f"{verdict}; {'closer to' if closer else 'no closer to'} it than greedy"))
    return claims


def _markdown(table: list[dict[str, Any]], strips: dict[str, int], claims: list[Claim], runs: int,
              time_limit: float, explorer: str) -> str:
    lines = ["# Drop rules in buildings", "",
             f"3 agents from one base station, explorer {explorer}, {runs} runs per cell, at most {time_limit:g} s; "
             "stock per agent (an agent out of routers goes on and may be cut off). Mean ± 95 % CI.", "",
             "| map | rule | radio | stock | relays used | time connected | runs cut off | longest outage (s) "
             "| coverage | reached 99 % |", "|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for e in table:
        lines.append(f"| {e['map']} | {e['rule']} | {e['radio']} | {e['stock']} | "
                     f"{mean_ci_text(e['relays_mean'], e['relays_ci95'])} | "
                     f"{mean_ci_text(100 * e['connected_mean'], 100 * e['connected_ci95'])} % | "
                     f"{e['runs_cut_off']}/{e['runs']} | {e['longest_outage_s']:g} | "
                     f"{100 * e['coverage_mean']:.1f} % | {e['reached_target']}/{e['runs']} |")
    lines += ["", "## Best rule per building (longest time connected; ties: fewer relays)", "",
              "| map | radio | stock | best rule | relays used | time connected |", "|---|---|---:|---|---:|---:|"]
    for name in strips:
        for radio in dict.fromkeys(e["radio"] for e in table):
            for stock in dict.fromkeys(e["stock"] for e in table):
                best = _best(table, name, radio, stock)
                if best is not None:
                    lines.append(f"| {name} | {radio} | {stock} | {best['rule']} | {best['relays_mean']:.1f} | "
                                 f"{100 * best['connected_mean']:.1f} % |")
    lines += ["", "Static r-strip on the free space each base station reaches (routers, base node not counted): "
              + ", ".join(f"{k} {v}" for k, v in strips.items()) + ".", ""]
    return "\n".join(lines) + "\n" + claims_markdown("What the paper's rules do in buildings", claims)


def _figure(table: list[dict[str, Any]], buildings: tuple[str, ...], radios: tuple[str, ...]) -> bytes:
    """Relays used vs time connected, one point per rule and stock, a panel per building and radio."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    rules = list(dict.fromkeys(e["rule"] for e in table))
    stocks = list(dict.fromkeys(e["stock"] for e in table))
    markers = ["o", "s", "^", "D", "v"]
    colours = [f"C{k}" for k in range(10)]
    fig = Figure(figsize=(3.2 * len(buildings), 3.0 * len(radios) + 0.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(radios), len(buildings), squeeze=False)
    for i, radio in enumerate(radios):
        for j, name in enumerate(buildings):
            ax = axes[i][j]
            opt = next((e for e in table if (e["map"], e["radio"]) == (name, radio) and "optimum_best" in e), None)
            if opt is not None:  # reproduce buildings --optimum: the lattice optimum, from its bound to its best
                ax.axvspan(opt["optimum_bound"], opt["optimum_best"], color="0.85", lw=0)
                ax.axvline(opt["optimum_best"], color="k", ls="--", lw=1)
            for e in table:
                if e["map"] != name or e["radio"] != radio:
                    continue
                ax.errorbar(e["relays_mean"], 100 * e["connected_mean"], xerr=e["relays_ci95"],
                            yerr=100 * e["connected_ci95"], fmt=markers[stocks.index(e["stock"]) % len(markers)],
                            color=colours[rules.index(e["rule"]) % len(colours)], capsize=2, ms=5)
            ax.set_title(f"{name}, {radio}", fontsize=9)
            ax.set_ylim(-3, 103)
            ax.set_xlim(left=0)
            ax.grid(True, alpha=0.3)
            if j == 0:
                ax.set_ylabel("time connected (%)")
            if i == len(radios) - 1:
                ax.set_xlabel("relays used")
    handles = [axes[0][0].plot([], [], "o", color=colours[k % len(colours)], label=r)[0] for k, r in enumerate(rules)]
    handles += [axes[0][0].plot([], [], markers[k % len(markers)], color="0.4", label=f"stock {s}")[0]
                for k, s in enumerate(stocks)]
    if any("optimum_best" in e for e in table):
        handles.append(axes[0][0].plot([], [], "k--", lw=1, label="optimum (grey: to bound)")[0])
    fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 8), fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()
