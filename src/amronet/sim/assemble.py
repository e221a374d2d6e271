"""Turn a validated scenario into a world and a swarm: map, reachable free space, base stations, routers."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from amronet.engine.coverage import CoverageArea
from amronet.engine.radio import RadioMedium, make_medium
from amronet.engine.robots import ROBOT_MODELS, RobotModel, Role, State, Swarm
from amronet.errors import MapError, ScenarioError
from amronet.scenario import RobotRef, RobotSpec, Scenario
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance, reachable_free, wall_distance
from amronet.world.trajectories import AgentPaths, load_trajectories

__all__ = ["World", "build_medium", "build_swarm", "build_world", "load_scenario_paths", "medium_needs_rng",
           "robot_model"]


@dataclass(frozen=True)
class World:
    """The static part of a run.

    Attributes:
        omap: The occupancy map.
        reachable: Free cells reachable from the base stations (the area that counts).
        coverage: Prepared coverage computation over ``reachable``.
        bases_xy: Base-station positions ``(n, 2)``.
    """

    omap: OccupancyMap
    reachable: np.ndarray
    coverage: CoverageArea
    bases_xy: np.ndarray


def medium_needs_rng(scenario: Scenario) -> bool:
    """Whether the scenario's radio draws random numbers (shadowing field, packet loss): one run per medium then."""
    return scenario.radio.packet_loss or scenario.radio.link_budget().shadowing_db > 0


def build_medium(scenario: Scenario, omap: OccupancyMap, rng: np.random.Generator | None,
                 packet_loss: bool | None = None) -> RadioMedium:
    """The scenario's radio medium over ``omap``.

    Args:
        scenario: The scenario (its ``radio``).
        omap: The map.
        rng: The run's generator (``None`` for a batch, which :func:`medium_needs_rng` must then deny). A fresh
            ``numpy.random.default_rng(seed)`` rebuilds a finished run's shadowing field exactly.
        packet_loss: Override the scenario's switch (``False`` for pictures of the usable links).
    """
    radio = scenario.radio
    loss = radio.packet_loss if packet_loss is None else packet_loss
    return make_medium(radio.model, radio.link_budget(), omap, rng=rng, packet_loss=loss)


def robot_model(ref: RobotRef, field: str) -> RobotModel:
    """Resolve a robot given by name or field by field."""
    if isinstance(ref, RobotSpec):
        return RobotModel("custom", ref.radius, ref.max_speed, ref.sensor_beams, ref.sensor_range)
    try:
        return ROBOT_MODELS[ref]
    except KeyError:
        raise ScenarioError(field, f"unknown robot {ref!r}; use one of {', '.join(ROBOT_MODELS)} or give "
                                   "radius, max_speed, sensor_beams and sensor_range") from None


def load_scenario_map(scenario: Scenario) -> OccupancyMap:
    """Load the scenario's map; relative paths are taken from the scenario file's folder."""
    ref = scenario.map
    looks_like_path = ref.lower().endswith((".yaml", ".yml")) or "/" in ref
    if looks_like_path and scenario.base_dir and not Path(ref).is_absolute():
        ref = str(Path(scenario.base_dir) / ref)
    try:
        return resolve_map(ref)
    except MapError as exc:
        if exc.field.startswith("map"):
            raise
        raise MapError("map", exc.message) from None


def load_scenario_paths(scenario: Scenario, world: World) -> AgentPaths | None:
    """Read and check the agents' trajectory file against the world (``None`` when the scenario gives none)."""
    path = scenario.trajectories_path()
    if path is None:
        return None
    n_agents = scenario.agents.per_base * len(scenario.base_stations)
    return load_trajectories(path, world.omap, n_agents, reachable=world.reachable,
                             time_limit=scenario.sim.time_limit, shown=str(scenario.agents.trajectories))


def build_world(scenario: Scenario, omap: OccupancyMap | None = None) -> World:
    """Load the map (unless given), check the base stations and prepare the area that counts."""
    omap = omap if omap is not None else load_scenario_map(scenario)
    bases = np.array([[b.x, b.y] for b in scenario.base_stations], dtype=float)
    inside = omap.inside(bases)
    free = omap.is_free(bases)
    for i, (x, y) in enumerate(bases):
        where = f"({x:g}, {y:g})"
        if not inside[i]:
            xmin, xmax, ymin, ymax = omap.extent
            raise ScenarioError(
                f"base_stations[{i}]", f"{where} is outside the map [{xmin:g}, {xmax:g}] x [{ymin:g}, {ymax:g}]; "
                "move it inside",
            )
        if not free[i]:
            raise ScenarioError(f"base_stations[{i}]", f"{where} is inside an obstacle or unknown space; "
                                "move it to free space")
    clear = clearance(omap)
    rows, cols = omap.world_to_cell(bases)
    bodies = [robot_model(spec.robot, f"base_stations[{i}].robot").radius
              for i, spec in enumerate(scenario.base_stations)]
    for j in range(1, len(bases)):  # a handful of base stations: pairs in plain Python
        for i in range(j):
            gap, need = float(np.linalg.norm(bases[j] - bases[i])), bodies[i] + bodies[j]
            if gap < need:
                raise ScenarioError(f"base_stations[{j}]", f"({bases[j][0]:g}, {bases[j][1]:g}) is {gap:.3g} m "
                                    f"from base_stations[{i}] ({bases[i][0]:g}, {bases[i][1]:g}), but their "
                                    f"reference nodes' bodies need {need:.3g} m; move one of them")
    for i, spec in enumerate(scenario.base_stations):
        body = bodies[i]
        if clear[rows[i], cols[i]] < body:
            raise ScenarioError(
                f"base_stations[{i}]", f"({spec.x:g}, {spec.y:g}) is {clear[rows[i], cols[i]]:.3g} m from an obstacle, "
                f"too close for the reference node's body (radius {body:g} m); move it farther from the walls",
            )
    reachable = reachable_free(omap, bases)
    return World(omap=omap, reachable=reachable, coverage=CoverageArea(omap, reachable), bases_xy=bases)


def _sample_start(
    world: World, centre: np.ndarray, region: tuple[float, float], count: int, radius: float, max_dist: float,
    taken: np.ndarray, taken_r: np.ndarray, rng: np.random.Generator, field: str,
) -> np.ndarray:
    """Draw ``count`` non-overlapping start points in the region, in reachable free space, near the base."""
    omap = world.omap
    clear = clearance(omap)
    placed: list[np.ndarray] = []
    pts = np.zeros((0, 2))
    others = taken.copy()
    others_r = taken_r.copy()
    for _ in range(200):
        if len(pts) >= count:
            break
        cand = centre + (rng.random((4 * count + 16, 2)) - 0.5) * np.asarray(region)
        rows, cols = omap.world_to_cell(cand)
        ok = omap.inside(cand)
        ok[ok] &= world.reachable[rows[ok], cols[ok]] & (clear[rows[ok], cols[ok]] >= radius)
        ok[ok] &= wall_distance(omap, cand[ok], cap=2.0 * radius) >= radius  # the body, exactly clear of walls
        ok &= np.linalg.norm(cand - centre, axis=1) <= max_dist
        for p in cand[ok]:
            if len(pts) >= count:
                break
            if len(others) and np.any(np.linalg.norm(others - p, axis=1) < others_r + radius):
                continue
            placed.append(p)
            pts = np.asarray(placed)
            others = np.vstack([others, p])
            others_r = np.append(others_r, radius)
    if len(pts) < count:
        # random draws jam when the free part is tight (the first bodies block the rest): pack deterministically
        packed = _pack_start(world, centre, region, count, radius, max_dist, taken, taken_r)
        if len(packed) < count:
            best = max(len(pts), len(packed))
            raise ScenarioError(field, f"could place only {best} of {count} robots without overlap in the start "
                                       f"region ({region[0]:g} m x {region[1]:g} m); "
                                       + _region_advice(world, centre, region, count, radius, max_dist, taken,
                                                        taken_r))
        return packed
    return pts


def _region_advice(
    world: World, centre: np.ndarray, region: tuple[float, float], count: int, radius: float, max_dist: float,
    taken: np.ndarray, taken_r: np.ndarray,
) -> str:
    """What to do about a start region too small for its robots: the smallest region that holds them here, if any.

    The region is scaled up (its proportions kept, sides rounded up to 0.1 m) until the start packing places every
    robot on this map; beyond the square that holds the disc of ``max_dist`` (where robots may start) a larger
    region adds nothing.
    """
    def sides(f: float) -> tuple[float, float]:
        return (float(np.ceil(region[0] * f * 10 - 1e-9)) / 10, float(np.ceil(region[1] * f * 10 - 1e-9)) / 10)

    def fits(f: float) -> bool:
        return len(_pack_start(world, centre, sides(f), count, radius, max_dist, taken, taken_r)) >= count

    lo, hi = 1.0, max(1.0, 2.0 * max_dist / min(region)) * 1.01
    if not fits(hi):
        return (f"no region holds them within {max_dist:.3g} m of the base station (where they hear it): move it "
                "away from the walls, use fewer robots or raise radio.r_c")
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    w, h = sides(hi)
    return f"a region of {w:g} m x {h:g} m holds them here: enlarge the base station's region, or use fewer robots"


_PACK_LATTICE_MAX = 1_000_000
"""Most lattice points the deterministic start packing looks at (a coarser lattice for larger regions)."""
_PACK_SEED = 20240518
"""Seed of the fixed shuffles the start packing tries after its ordered sweeps."""
_PACK_WORK = 20_000_000
"""Rough budget of point visits for those shuffles (16 to 256 of them)."""


def _start_lattice(
    world: World, centre: np.ndarray, region: tuple[float, float], radius: float, max_dist: float
) -> np.ndarray:
    """Points of a lattice over the start region where a body of ``radius`` may stand, and which are clear.

    The lattice divides every map cell into ``k x k`` points (a quarter cell apart or finer, and finer than half a
    body), plus the region's edges (a sliver of free space along an edge is not lost between lattice points). A
    point qualifies as a random draw does: it lies in the region and within ``max_dist`` of ``centre``, and its
    cell is reachable free space with a clearance of at least ``radius``.

    Returns:
        ``(points (M, 2), clear (M,))``: ``clear`` marks the points whose body keeps clear of every wall's square
        (:func:`~amronet.world.space.wall_distance` at least ``radius``).
    """
    omap = world.omap
    res = float(omap.resolution)
    n_rows, n_cols = omap.shape
    half = 0.5 * np.asarray(region, dtype=float)
    lo, hi = centre - half, centre + half
    k = max(4, int(np.ceil(2.0 * res / radius))) if radius > 0 else 4  # points per cell and axis
    cells = (half[0] / res + 1) * (half[1] / res + 1) * 4
    step = res / k if cells * k * k <= _PACK_LATTICE_MAX else res * max(1.0, np.sqrt(cells / _PACK_LATTICE_MAX))

    def axis(a: int, n_cells: int) -> np.ndarray:
        origin = float(omap.origin[a])
        first = origin + (np.floor((max(lo[a], origin) - origin) / step) + 0.5) * step
        last = min(hi[a], origin + n_cells * res)
        inner = np.arange(first, last + 0.5 * step, step)
        v = np.unique(np.concatenate([inner, [lo[a], hi[a]]]))
        return v[(v >= lo[a]) & (v <= hi[a])]

    gx, gy = np.meshgrid(axis(0, n_cols), axis(1, n_rows))
    xy = np.stack([gx.ravel(), gy.ravel()], axis=1)
    xy = xy[omap.inside(xy) & (np.linalg.norm(xy - centre, axis=1) <= max_dist)]
    rows, cols = omap.world_to_cell(xy)
    room = clearance(omap)[rows, cols]
    ok = world.reachable[rows, cols] & (room >= radius)
    xy, rows, cols, room = xy[ok], rows[ok], cols[ok], room[ok]
    return xy, wall_distance(omap, xy, cap=2.0 * radius) >= radius


def _pack_start(
    world: World, centre: np.ndarray, region: tuple[float, float], count: int, radius: float, max_dist: float,
    taken: np.ndarray, taken_r: np.ndarray,
) -> np.ndarray:
    """Deterministic packing of ``count`` bodies into the start region, after the random draws failed.

    Greedy over the points of :func:`_start_lattice` clear of the bodies already placed: take the first point in
    a fixed order, drop every point its body would overlap, repeat. The orders, tried in turn until one places
    ``count``: nearest the base first; sweeps from each of the region's four corners, row by row and column by
    column; farthest from the base first; then greedy passes in shuffled orders from a fixed seed (the same for
    every run). Only points whose body keeps exactly clear of the walls are used (as a random draw requires).
    Returns the fullest placement (fewer than ``count`` if none fits).
    """
    cand, clear = _start_lattice(world, centre, region, radius, max_dist)
    near = np.linalg.norm(taken - centre, axis=1) <= 0.5 * float(np.hypot(*region)) + radius + taken_r
    for q, q_r in zip(taken[near], taken_r[near], strict=True):
        free = np.sum((cand - q) ** 2, axis=1) >= (radius + q_r) ** 2
        cand, clear = cand[free], clear[free]
    return _greedy_pack(cand[clear], centre, count, radius)


def _greedy_pack(cand: np.ndarray, centre: np.ndarray, count: int, radius: float) -> np.ndarray:
    """The greedy passes of :func:`_pack_start` over the points ``cand``; the fullest placement."""
    if len(cand) == 0:
        return np.zeros((0, 2))
    d = np.linalg.norm(cand - centre, axis=1)
    x, y = cand[:, 0], cand[:, 1]
    orders = [np.argsort(d, kind="stable")]
    orders += [np.lexsort((sx * x, sy * y)) for sy in (1, -1) for sx in (1, -1)]
    orders += [np.lexsort((sy * y, sx * x)) for sx in (1, -1) for sy in (1, -1)]
    orders.append(np.argsort(-d, kind="stable"))
    shuffle = np.random.default_rng(_PACK_SEED)  # not the run's: the packing does not depend on the seed
    restarts = int(np.clip(_PACK_WORK // (len(cand) * count), 16, 256))
    best = np.zeros((0, 2))
    reach2 = (2.0 * radius) ** 2
    for k in range(len(orders) + restarts):
        order = orders[k] if k < len(orders) else shuffle.permutation(len(cand))
        pool = cand[order]
        placed = []
        while len(pool) and len(placed) < count:
            p = pool[0]
            placed.append(p)
            pool = pool[np.sum((pool - p) ** 2, axis=1) >= reach2]
        if len(placed) > len(best):
            best = np.asarray(placed)
        if len(best) >= count:
            break
    return best


def _scatter(
    world: World, count: int, radius: float, taken: np.ndarray, taken_r: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Scatter ``count`` robots uniformly over the reachable free space, dropping those that would overlap."""
    omap = world.omap
    rows, cols = np.nonzero(world.reachable & (clearance(omap) >= radius))
    if len(rows) == 0:
        raise ScenarioError("routers.start", "no reachable free cell is wide enough for a router")
    out = np.zeros((0, 2))
    for _ in range(50):
        need = count - len(out)
        if need <= 0:
            break
        pick = rng.integers(0, len(rows), size=need)
        jitter = (rng.random((need, 2)) - 0.5) * omap.resolution
        cand = omap.cell_centres(rows[pick], cols[pick]) + jitter
        pool = np.vstack([taken, out, cand])
        pool_r = np.concatenate([taken_r, np.full(len(out) + need, radius)])
        tree = cKDTree(pool)
        pairs = tree.query_pairs(2 * max(radius, float(pool_r.max())), output_type="ndarray")
        gap = np.linalg.norm(pool[pairs[:, 0]] - pool[pairs[:, 1]], axis=1) if len(pairs) else np.zeros(0)
        clash = pairs[gap < pool_r[pairs[:, 0]] + pool_r[pairs[:, 1]]] if len(pairs) else pairs
        first_new = len(taken) + len(out)
        bad = np.zeros(len(pool), dtype=bool)
        # of every clashing pair drop the later robot (a new candidate), so earlier placements stay
        if len(clash):
            bad[np.maximum(clash[:, 0], clash[:, 1])] = True
        bad[first_new:] |= wall_distance(omap, cand, cap=2.0 * radius) < radius  # bodies exactly clear of walls
        out = np.vstack([out, cand[~bad[first_new:]]])
    if len(out) < count:
        raise ScenarioError("routers.count", f"could scatter only {len(out)} of {count} routers without overlap; "
                                             "use fewer routers or a larger map")
    return out[:count]


def build_swarm(scenario: Scenario, world: World, rng: np.random.Generator, r_start: float) -> Swarm:
    """Place base reference nodes, routers (round-robin over base stations) and agents, random in each region.

    Args:
        scenario: The scenario.
        world: Its world.
        rng: The run's generator (start positions and headings are drawn from it).
        r_start: Routers start within this distance of their base's reference node, so that they hear it.
    """
    groups = []
    base_models = [robot_model(b.robot, f"base_stations[{i}].robot") for i, b in enumerate(scenario.base_stations)]
    for i, model in enumerate(base_models):
        groups.append((model, Role.BASE, State.BASE, world.bases_xy[i : i + 1], np.array([i])))
    router = robot_model(scenario.routers.robot, "routers.robot")
    n_bases = len(scenario.base_stations)
    counts = [len(range(i, scenario.routers.count, n_bases)) for i in range(n_bases)]
    taken = world.bases_xy.copy()
    taken_r = np.array([k.radius for k in base_models])
    if scenario.routers.start == "uniform":
        pts = _scatter(world, scenario.routers.count, router.radius, taken, taken_r, rng)
        taken = np.vstack([taken, pts])  # agents placed below must not land on a scattered router
        taken_r = np.append(taken_r, np.full(len(pts), router.radius))
        groups.append((router, Role.ROUTER, State.EXPLORE, pts, np.full(len(pts), -1)))
        counts = []
    for i, count in enumerate(counts):
        if count == 0:
            continue
        spec = scenario.base_stations[i]
        pts = _sample_start(world, world.bases_xy[i], spec.region, count, router.radius, r_start, taken, taken_r,
                            rng, f"base_stations[{i}].region")
        taken = np.vstack([taken, pts])
        taken_r = np.append(taken_r, np.full(len(pts), router.radius))
        groups.append((router, Role.ROUTER, State.EXPLORE, pts, np.full(count, -1)))
    per_base = scenario.agents.per_base
    if per_base:
        agent = robot_model(scenario.agents.robot, "agents.robot")
        for i, spec in enumerate(scenario.base_stations):
            pts = _sample_start(world, world.bases_xy[i], spec.region, per_base, agent.radius, r_start, taken,
                                taken_r, rng, f"base_stations[{i}].region")
            taken = np.vstack([taken, pts])
            taken_r = np.append(taken_r, np.full(len(pts), agent.radius))
            groups.append((agent, Role.AGENT, State.AGENT, pts, np.full(per_base, i)))
    swarm = Swarm.build(groups)
    swarm.heading[:] = rng.uniform(-np.pi, np.pi, size=len(swarm))
    return swarm
