"""The resource guard of a run: a scenario's robots, steps and map against :mod:`amronet.limits`, before set-up.

:class:`~amronet.sim.loop.Loop` calls :func:`check_scenario` before it loads the map and :func:`check_world` after
the map is loaded and before anything is built on it; a sweep calls :func:`check_scenario` for each point. Refused,
each is one :class:`~amronet.errors.ScenarioError` naming the field to change:

* **bodies that cannot fit** (always refused): the routers (and agents) of a base station need more floor for their
  bodies than their start region offers — the region's rectangle, and the disc around the base within which a
  robot must start, both grown by a body's radius; with ``routers.start: uniform``, more than the whole map;
* **memory** (always refused): ``BYTES_PER_ROBOT`` per robot, ``BYTES_PER_LINK`` per link of the densest start
  (the robots of a start region within ``r_c`` of each other, at most as many as fit in a disc of ``r_c``), times
  the runs stepped together, plus ``BYTES_PER_MAP_CELL`` per map cell, against the memory available now;
* **absurd work** (refused unless acknowledged, ``force``): more than ``MAX_STEPS`` steps
  (``sim.time_limit / sim.dt``) or ``MAX_ROBOT_STEPS`` robots times steps in one run.
"""

from __future__ import annotations

import math

from amronet import limits
from amronet.errors import ScenarioError
from amronet.scenario import Scenario
from amronet.scenario.defaults import fitted_side
from amronet.sim.assemble import robot_model
from amronet.world.occupancy import OccupancyMap

__all__ = ["check_scenario", "check_world", "run_steps"]


def run_steps(scenario: Scenario) -> float:
    """The most steps a run of ``scenario`` takes: ``sim.time_limit / sim.dt`` (a float: it may be huge)."""
    return scenario.sim.time_limit / scenario.sim.dt


def _robots(scenario: Scenario) -> tuple[int, int, int]:
    """Base nodes, routers and agents of one run at its start (the routers agents release later are not known)."""
    sc = scenario
    n_bases = len(sc.base_stations)
    return n_bases, sc.routers.count, sc.agents.per_base * n_bases


def _culprit(scenario: Scenario) -> str:
    """The count to name when robots are too many: routers, or agents when they are more."""
    _, routers, agents = _robots(scenario)
    return "agents.per_base" if agents > routers else "routers.count"


def _check_bodies(scenario: Scenario, r_start: float) -> float:
    """Refuse start regions that cannot hold their robots' bodies; return the mean degree of the densest start."""
    sc = scenario
    n_bases = len(sc.base_stations)
    router = robot_model(sc.routers.robot, "routers.robot").radius
    agent = robot_model(sc.agents.robot, "agents.robot").radius if sc.agents.per_base else 0.0
    smallest = min(router, agent) if agent else router
    degree = 0.0
    for i, base in enumerate(sc.base_stations):
        routers = len(range(i, sc.routers.count, n_bases)) if sc.routers.start == "base" else 0
        agents = sc.agents.per_base
        if routers + agents == 0:
            continue
        w, h = base.region
        grow = max(router if routers else 0.0, agent if agents else 0.0)
        disc = math.pi * (r_start + grow) ** 2
        room = min((w + 2 * grow) * (h + 2 * grow), disc)
        need = math.pi * (routers * router**2 + agents * agent**2)
        if need > room:
            field = ("routers.count" if math.pi * routers * router**2 > room else
                     "agents.per_base" if math.pi * agents * agent**2 > room else f"base_stations[{i}].region")
            what = " and ".join(f"{n} {kind} (radius {r:g} m)" for n, kind, r in
                                ((routers, "routers", router), (agents, "agents", agent)) if n)
            side = fitted_side(routers + agents, grow, robot_model(base.robot, f"base_stations[{i}].robot").radius)
            fix = (f"a {side:g} m x {side:g} m region holds them in open floor" if side <= math.sqrt(2) * r_start else
                   f"no region does within {r_start:.3g} m; raise radio.r_c")
            raise ScenarioError(field, f"{what} need {need:.3g} m² of floor for their bodies, but the start region "
                                       f"of base_stations[{i}] ({w:g} m x {h:g} m, within {r_start:.3g} m of the "
                                       f"base) offers at most {room:.3g} m²; use fewer robots or enlarge "
                                       f"base_stations[{i}].region ({fix})")
        density = (routers + agents) / (w * h)
        fit = (sc.radio.r_c + smallest) ** 2 / smallest**2  # bodies that fit in a disc of r_c around one
        degree = max(degree, min(density * math.pi * sc.radio.r_c**2, fit, routers + agents - 1.0))
    return degree


def _robot_bytes(robots: int, degree: float) -> float:
    return robots * (limits.BYTES_PER_ROBOT + degree * limits.BYTES_PER_LINK)


def check_scenario(scenario: Scenario, runs: int = 1, r_start: float | None = None, force: bool = False,
                   acknowledge: str = limits.ACKNOWLEDGE) -> None:
    """Refuse, before the map is loaded, runs whose robots cannot fit or would take absurdly long.

    Args:
        scenario: The validated scenario.
        runs: Runs stepped together in one loop (a batch holds the robots of each).
        r_start: How close to its base a robot starts (the algorithm's ``start_range``; default ``r_c``).
        force: The user acknowledged absurd work (``--force``): steps and robot-steps are not bounded then.
        acknowledge: How the user can acknowledge absurd work, as the message ends.

    Raises:
        ScenarioError: Bodies that cannot fit in their start region, memory that is not there, or (without
            ``force``) absurd work; one line naming the field (see the module docstring).
    """
    sc = scenario
    n_bases, routers, agents = _robots(sc)
    robots = n_bases + routers + agents
    degree = _check_bodies(sc, sc.radio.r_c if r_start is None else r_start)
    field = _culprit(sc)
    limits.check_memory(runs * _robot_bytes(robots, degree), field,
                        f"{robots} robots" + (f" in each of {runs} runs" if runs > 1 else ""),
                        f"use fewer {field.split('.')[0]}" + (" or fewer seeds at once" if runs > 1 else ""))
    steps = run_steps(sc)
    if not math.isfinite(steps) or steps >= 2**62:
        raise ScenarioError("sim.dt", f"sim.time_limit {sc.sim.time_limit:g} s / sim.dt {sc.sim.dt:g} s is not a "
                                      "countable number of steps; raise sim.dt or lower sim.time_limit")
    long_dt = 0.1 / sc.sim.dt > max(sc.sim.time_limit / 300.0, 1.0)  # the one farther from its default is to blame
    limits.check_work(steps, limits.MAX_STEPS, "sim.dt" if long_dt else "sim.time_limit",
                      f"sim.time_limit {sc.sim.time_limit:g} s / sim.dt {sc.sim.dt:g} s = "
                      f"{limits.format_count(steps)} steps",
                      "raise sim.dt or lower sim.time_limit", force, acknowledge=acknowledge)
    limits.check_work(steps * robots, limits.MAX_ROBOT_STEPS, field,
                      f"{robots} robots x {limits.format_count(steps)} steps = {limits.format_count(steps * robots)} "
                      "robot-steps",
                      f"use fewer {field.split('.')[0]} or a shorter sim.time_limit", force,
                      acknowledge=acknowledge)


def check_world(scenario: Scenario, omap: OccupancyMap, runs: int = 1, r_start: float | None = None) -> None:
    """Refuse, once the map is loaded and before anything is built on it, runs that cannot fit with it.

    Args:
        scenario: The validated scenario (already through :func:`check_scenario`).
        omap: Its map.
        runs: Runs stepped together in one loop.
        r_start: How close to its base a robot starts (default ``r_c``).

    Raises:
        ScenarioError: Routers scattered over the map (``routers.start: uniform``) whose bodies exceed the map, or
            the map and the robots together need more memory than there is.
    """
    sc = scenario
    n_bases, routers, agents = _robots(sc)
    robots = n_bases + routers + agents
    cells = omap.cells.size
    degree = _check_bodies(sc, sc.radio.r_c if r_start is None else r_start)
    if sc.routers.start == "uniform" and sc.routers.count:
        radius = robot_model(sc.routers.robot, "routers.robot").radius
        w, h = omap.size_m
        room = (w + 2 * radius) * (h + 2 * radius)
        need = math.pi * sc.routers.count * radius**2
        if need > room:
            raise ScenarioError("routers.count", f"{sc.routers.count} routers (radius {radius:g} m) need {need:.3g} "
                                                 f"m² of floor for their bodies, more than the whole map "
                                                 f"({w:g} m x {h:g} m); use fewer routers")
        free = max(float(omap.free.sum()) * omap.resolution**2, 1e-12)
        fit = (sc.radio.r_c + radius) ** 2 / radius**2
        degree = max(degree, min(sc.routers.count * math.pi * sc.radio.r_c**2 / free, fit, robots - 1.0))
    robot_bytes = runs * _robot_bytes(robots, degree)
    map_bytes = cells * limits.BYTES_PER_MAP_CELL
    if map_bytes >= robot_bytes:
        field, fix = "map", "use a coarser map (a larger resolution, fewer cells)"
    else:
        field = _culprit(sc)
        fix = f"use fewer {field.split('.')[0]}"
    limits.check_memory(map_bytes + robot_bytes, field,
                        f"a map of {omap.shape[1]} x {omap.shape[0]} cells with {robots} robots"
                        + (f" in each of {runs} runs" if runs > 1 else ""), fix)
