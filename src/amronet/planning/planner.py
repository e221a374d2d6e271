"""The planner: three answers to how many routers a team must carry (see :mod:`amronet.planning`)."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from amronet import limits
from amronet.algorithms.agent_assisted import AgentAssistedParams
from amronet.engine.robots import ROBOT_MODELS
from amronet.errors import AmronetError, MapError, ScenarioError
from amronet.experiments.common import agent_scenario
from amronet.experiments.options import AGENT_TIME_LIMIT_S, RunOptions
from amronet.patterns import as_area, place_all
from amronet.planning.report import PLAN_ESTIMATE_DENSITY, Plan
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sweeps import LocalExecutor, ResultStore, run_sweep, sweep_from_spec
from amronet.sweeps.store import check_store_path
from amronet.world import reachable_free, resolve_map
from amronet.world.builtin import BUILTIN_MAPS

__all__ = ["PAPER_MISSION", "Mission", "connected_distribution", "plan"]


class Mission(NamedTuple):
    """How the agents fly the planned mission, beyond the map and the team: the radio, the drop rule, the stock.

    Attributes:
        radio: Radio fields beyond ``r_c`` (e.g. ``{"model": "multi-wall", "shadowing_db": 4}``); ``None``: the
            unit disk.
        drop_rule: The agents' drop rule (``None``: the paper's ``last-reference``).
        drop: The drop rule's parameters.
        stock: Routers each agent carries (``None``: unlimited). With a stock an agent that runs out goes on and
            may be cut off (``when_empty`` ``continue``, unless given): a plan must show the outages a short stock
            causes. The relays distribution is then taken over every finished run, since a stock-limited run may
            not reach the coverage target.
        when_empty: ``tether`` or ``continue`` (``agents.when_empty``).
        settle_s: ``agents.drop_settle_s``.
        reverse_drop: ``agents.reverse_drop``.
        trajectories: A CSV of the agents' paths (``agents.trajectories``): the plan of a replayed or planned
            mission. Its runs end where the paths end, not at a coverage target, so the relays distribution is
            taken over every finished run.
    """

    radio: dict[str, Any] | None = None
    drop_rule: str | None = None
    drop: dict[str, Any] | None = None
    stock: int | None = None
    when_empty: str | None = None
    settle_s: float | None = None
    reverse_drop: float | None = None
    trajectories: str | Path | None = None


PAPER_MISSION = Mission()
"""The paper's mission: the unit disk, last-reference drops, an unlimited stock."""


def _check(option: str, ok: bool, message: str) -> None:
    if not ok:
        raise AmronetError(f"{option}: {message}")


_OPTION_OF_FIELD = (("radio", "--radio"), ("algorithm.params.drop_rule", "--drop-rule"),
                    ("algorithm.params.drop", "--drop"), ("agents.routers_carried", "--stock"),
                    ("agents.when_empty", "--when-empty"), ("agents.drop_settle_s", "--settle-s"),
                    ("agents.reverse_drop", "--reverse-drop"), ("agents.trajectories", "--trajectories"))
"""Scenario fields the planner's options set → the option, for one-line errors that name what the user typed."""


def _scenario(map_ref: str, bases: list[tuple[float, float]], r_c: float, agents: int, explorer: str,
              time_limit: float, dt: float, mission: dict[str, Any] | None = None) -> dict[str, Any]:
    sc = agent_scenario(map_ref, r_c, tuple(bases), agents, explorer, time_limit, dt=dt, **(mission or {}))
    if map_ref not in BUILTIN_MAPS:
        sc["map"] = str(Path(map_ref).resolve())
        sc["name"] = f"agent-assisted-{Path(map_ref).stem}"
    return sc


def plan(map_ref: str, bases: list[tuple[float, float]], r_c: float, agents_per_base: int, runs: int = 20,
         confidence: float = 0.95, dt: float = 0.25, options: RunOptions | None = None, *,
         mission: Mission = PAPER_MISSION) -> Plan:
    """Plan a deployment (see the module docstring).

    Args:
        map_ref: Built-in map name or ROS map_server YAML path.
        bases: Base-station positions ``(x, y)`` in metres; each in free space.
        r_c: Communication radius in metres.
        agents_per_base: Agents per base station (>= 1).
        runs: Agent-assisted runs ``K``.
        confidence: Quantile of the recommendation, in (0, 1].
        dt: Simulation step.
        options: How the runs are made (default ``RunOptions(show_progress=False)``): the agents' ``explorer``;
            ``time_limit`` (default :data:`~amronet.experiments.options.AGENT_TIME_LIMIT_S`); ``seed``, the first
            seed (runs use ``seed .. seed + K - 1``); ``store``, the result store to keep the runs in (and reuse),
            ``None`` for a temporary one; ``workers`` (local processes, when there is no ``executor``);
            ``executor`` (e.g. Dask); ``show_progress`` (the sweep's progress bar); ``retry_failed``: run again
            the runs that ``store`` holds as failed (otherwise they stay failed, as with ``amronet sweep``, and the
            plan warns about them).
        mission: The radio, the drop rule and the agents' stock (:class:`Mission`; default the paper's: unit disk,
            last-reference drops, unlimited stock).

    Raises:
        AmronetError: Bad input, with one line naming the option.
    """
    options = options or RunOptions(show_progress=False)
    stock, when_empty, trajectories = mission.stock, mission.when_empty, mission.trajectories
    explorer, seed, store = options.explorer, options.seed, options.store
    time_limit = options.time_limit_or(AGENT_TIME_LIMIT_S)
    _check("--rc", math.isfinite(r_c) and r_c > 0, f"must be a finite number > 0 (metres), got {r_c:g}")
    _check("--agents", agents_per_base >= 1, f"must be >= 1 agent per base station, got {agents_per_base}")
    _check("--runs", runs >= 1, f"must be >= 1, got {runs}")
    _check("--confidence", 0 < confidence <= 1, f"must be in (0, 1], e.g. 0.95, got {confidence:g}")
    _check("--base", len(bases) >= 1, "give at least one base station as --base X,Y")
    _check("--seed", seed >= 0, f"must be >= 0, got {seed}")
    omap = resolve_map(map_ref)
    try:
        mask = reachable_free(omap, np.array(bases, dtype=float))
    except MapError as exc:
        raise AmronetError(f"--base: {exc.message}") from None
    area = float(mask.sum()) * omap.resolution**2
    _check("--stock", stock is None or stock >= 0, f"must be >= 0 routers per agent, got {stock}")
    agents_fields: dict[str, Any] = {}
    if stock is not None:
        agents_fields.update(routers_carried=int(stock), when_empty=when_empty or "continue")
    elif when_empty is not None:
        agents_fields["when_empty"] = when_empty
    for key, value in (("drop_settle_s", mission.settle_s), ("reverse_drop", mission.reverse_drop)):
        if value is not None:
            agents_fields[key] = float(value)
    if trajectories is not None:
        agents_fields["trajectories"] = str(Path(trajectories).resolve())
    fields = {"radio": mission.radio, "drop_rule": mission.drop_rule, "drop": mission.drop,
              "agents": agents_fields or None}
    scenario = _scenario(map_ref, bases, r_c, agents_per_base, explorer, time_limit, dt, fields)
    step, band = ROBOT_MODELS[scenario["agents"]["robot"]].max_speed * dt, AgentAssistedParams().loss_margin
    _check("--rc", band * r_c > step, f"{r_c:g} m leaves the agents an 'about to lose' band ({100 * band:g} % of r_c) "
           f"no wider than one of their steps ({step:g} m); give --rc above {step / band:.3g} m")
    _check("--time-limit", time_limit / dt <= limits.MAX_STEPS, f"{time_limit:g} s is more than "
           f"{limits.format_count(limits.MAX_STEPS)} steps of {dt:g} s per run; lower --time-limit")
    try:
        Simulation(load_scenario(scenario), seed)  # fail fast, here, on a scenario that cannot start
    except MapError as exc:
        raise AmronetError(f"--base: {exc.message}" if exc.field.startswith("base_stations") else str(exc)) from None
    except ScenarioError as exc:
        option = next((o for f, o in _OPTION_OF_FIELD if exc.field == f or exc.field.startswith(f + ".")), None)
        raise AmronetError(f"{option}: {exc.field}: {exc.message}" if option else str(exc)) from None
    if store is not None:
        check_store_path(Path(store))
    placements = place_all(as_area(omap, mask=mask, r=r_c), r_c)
    patterns = {name: {"placed": p.count, "estimated": p.estimate, "coverage": p.coverage, "connected": p.connected}
                for name, p in placements.items()}
    sweep = sweep_from_spec({"name": f"plan-{scenario['name'].removeprefix('agent-assisted-')}", "base": scenario,
                             "seeds": runs, "seed_start": seed})
    with tempfile.TemporaryDirectory(prefix="amronet-plan-") as tmp:
        store_path = Path(store) if store is not None else Path(tmp) / "results.sqlite"
        run_sweep(sweep, store_path, options.executor or LocalExecutor(options.workers),
                  retry_failed=options.retry_failed, show_progress=options.show_progress)
        point = sweep.points[0]
        with ResultStore(store_path, must_exist=True) as st:
            outcomes = {s: st.load(point.hash, s, timeseries=False) for s in sweep.seeds}
    rows = []
    for s, out in outcomes.items():
        summ = out["summary"] or {}
        report = summ.get("mission") or {}
        rows.append({"seed": s, "status": out["status"], "routers_deployed": summ.get("routers_deployed"),
                     "nodes_total": summ.get("nodes_total"), "coverage": summ.get("coverage"),
                     "stop_reason": summ.get("stop_reason"), "sim_time_s": summ.get("sim_time_s"),
                     "agents_connected_min": summ.get("agents_connected_min"),
                     "connected_fraction": report.get("connected_fraction"), "outages": report.get("outages"),
                     "longest_outage_s": report.get("longest_outage_s"), "relays_used": report.get("relays_used"),
                     "error": out["error"]})
    target = float(load_scenario(scenario).sim.coverage_target or 0.99)
    done = [r for r in rows if r["status"] == "done"]
    completed = [r for r in done if r["stop_reason"] == "coverage_target"]
    if stock is not None or trajectories is not None:  # runs that may not reach the target: every finished run counts
        completed = done
    warnings = []
    failed = [r for r in rows if r["status"] == "failed"]
    if failed:
        retry = " (--retry-failed runs them again)" if store is not None else ""
        warnings.append(f"{len(failed)} of {runs} runs failed{retry}: {failed[0]['error']}")
    short = [r for r in rows if r["status"] == "done" and r["stop_reason"] != "coverage_target"]
    if short and stock is None and trajectories is None:
        warnings.append(f"{len(short)} of {runs} runs did not reach {100 * target:g} % coverage within "
                        f"{time_limit:g} s (left out; raise --time-limit)")
    values = np.array([r["routers_deployed"] for r in completed], dtype=float)
    distribution: dict[str, Any] = {"runs": runs, "completed": len(completed),
                                    "reached_target": sum(r["stop_reason"] == "coverage_target" for r in done)}
    recommended = typical = None
    if len(values):
        median = float(np.median(values))
        quantile = float(np.percentile(values, 100 * confidence))
        distribution.update(min=int(values.min()), median=median, mean=float(values.mean()), quantile=quantile,
                            max=int(values.max()))
        recommended = math.ceil(quantile - 1e-9)
        typical = min(completed, key=lambda r: (abs(r["routers_deployed"] - median), r["seed"]))["seed"]
    else:
        warnings.append("no run reached the coverage target, so there is no recommendation")
    connected = connected_distribution(done, confidence)
    if done and connected["cut_off_runs"] > 0.05 * len(done):
        worst = max(r["longest_outage_s"] or 0.0 for r in done)
        warnings.append(f"agents were cut off in {100 * connected['cut_off_runs'] / len(done):.0f} % of runs "
                        f"({connected['cut_off_runs']} of {len(done)}); longest outage {worst:g} s")
    n_agents = agents_per_base * len(bases)
    if stock is not None and any((r["relays_used"] or 0) >= stock * n_agents for r in done):
        ran_out = sum((r["relays_used"] or 0) >= stock * n_agents for r in done)
        warnings.append(f"the stock ran out ({stock} per agent, {stock * n_agents} in all) in {ran_out} of "
                        f"{len(done)} runs")
    if recommended is not None:
        distribution["per_agent"] = math.ceil(recommended / n_agents - 1e-9)
        if stock is not None and distribution["per_agent"] > stock:
            warnings.append(f"the recommendation, {distribution['per_agent']} per agent, exceeds --stock {stock}")
    return Plan(map=omap.name, bases=[tuple(map(float, b)) for b in bases], r_c=float(r_c),
                agents_per_base=agents_per_base, area_m2=area,
                estimate_nodes=math.ceil(PLAN_ESTIMATE_DENSITY * area / r_c**2 - 1e-9), patterns=patterns,
                runs=rows, confidence=confidence, distribution=distribution, recommended=recommended,
                typical_seed=typical, warnings=warnings, connected=connected,
                settings={"explorer": explorer, "time_limit": time_limit, "dt": dt, "coverage_target": target,
                          "radio": dict(mission.radio or {"model": "unit-disk"}),
                          "drop_rule": mission.drop_rule or "last-reference",
                          "stock": stock, "when_empty": agents_fields.get("when_empty", "tether"),
                          "trajectories": agents_fields.get("trajectories"), "seeds": list(sweep.seeds)},
                scenario=point.scenario)


def connected_distribution(done: list[dict[str, Any]], confidence: float) -> dict[str, Any]:
    """Time connected over the finished runs, and in how many runs some agent was cut off at least once.

    Min, median, mean, the pessimistic ``1 - confidence`` quantile and max of each run's connected fraction.
    """
    values = np.array([r["connected_fraction"] for r in done if r["connected_fraction"] is not None], dtype=float)
    out: dict[str, Any] = {"runs": len(done), "cut_off_runs": sum(1 for r in done if (r["outages"] or 0) > 0)}
    if len(values):
        out.update(min=float(values.min()), median=float(np.median(values)), mean=float(values.mean()),
                   quantile=float(np.percentile(values, 100 * (1 - confidence))), max=float(values.max()))
    return out
