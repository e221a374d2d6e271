"""Soak amronet: many random short scenarios, with invariants checked by code independent of the controllers.

Issue #18. Scenario ``i`` of a soak with seed ``S`` is drawn from the ``i``-th child of
``numpy.random.default_rng(S)`` (``Generator.spawn``), so any one of them can be rebuilt on its own. A draw picks a
built-in map, an algorithm from the registry with its parameters, a radio model (sometimes with shadowing or packet
loss), ``r_c``, 1-4 base stations at random free points of the map's largest free region with room around them,
routers or agents, robots (sometimes given field by field), ``dt`` and a short time limit. Each scenario runs in a
worker process with a wall-time limit; a worker that exceeds it is killed (a *hang*). Usage::

    .venv/bin/python tools/soak.py --count 1000 --seed 1 --jobs 2 --out soak.json
    .venv/bin/python tools/soak.py --replay 17 --seed 1            # one scenario again, in this process, verbose
    .venv/bin/python tools/soak.py --replay 17 --seed 1 --yaml s.yaml   # ... and its scenario file for amronet run

The run is stepped by hand and checked every few steps (every step for connectivity):

* ``not_finite``, ``centre_not_free``, ``centre_unreachable``: every robot's centre is a finite point in a free
  cell of the map, in the free space 4-connected to the base stations;
* ``body_in_wall``: every body is clear of every blocked cell (occupied, unknown, off the map), measured exactly
  from the centre to the cell's square, not from cell centres; the worst depth is reported;
* ``bodies_overlap``: with robot collisions on, no two bodies overlap (the worst depth and coincident pairs);
* the same kinds with ``_at_start`` (``body_in_wall_at_start``, ...) when seen before the first step: the start
  placement's;
* ``router_cut_off`` (self-spreading, agent-assisted): every deployed router has a path to a base station
  through deployed nodes in the step's neighbour table;
* ``agents_disconnected`` (agent-assisted): every agent hears a node with a path to a base station;
* ``coverage_range``: ``0 <= connected coverage <= coverage <= 1`` (every few recorded steps and at the end);
* ``nondeterministic``: every ``--determinism-every``-th scenario runs twice; final positions, headings, states
  and statuses must agree bit for bit.

The paper's distance rules promise connectivity only where a link is decided by distance: a ``router_cut_off``
under shadowing or packet loss, and an ``agents_disconnected`` anywhere but on the unit disk without packet loss
with unlimited routers, is counted as *known* (docs/radio.md, "What the paper's rules do under a real radio"), not as a
failure. A ``ScenarioError`` from loading or setting up a draw (e.g. a start region too small for its robots)
counts as *refused*. Any other exception is a *crash*. The exit status is 1 when there was a crash, a hang or a
failing violation, and every failure prints the one command that replays it.
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import time
import traceback
from collections import Counter
from dataclasses import dataclass
from functools import cache
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy import ndimage
from scipy.spatial import cKDTree

from amronet.algorithms import ALGORITHMS
from amronet.engine.network import agents_connected, connected_to
from amronet.engine.radio import MEDIA
from amronet.engine.robots import Role
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim.simulation import Simulation
from amronet.world.builtin import BUILTIN_MAPS, load_builtin_map
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance

ROOT = Path(__file__).resolve().parent.parent
FAILURE_KINDS = ("crash", "hang", "worker_died")
"""Outcomes that are failures by themselves (besides failing violations)."""
GEOMETRY_TOL = 1e-6
"""Metres a body may reach into a wall or into another body before it counts (floating-point slack)."""
SMALL_MAPS = ("open-6x6", "obstacles-6x6")
GEOMETRIC_KINDS = ("not_finite", "centre_not_free", "centre_unreachable", "body_in_wall", "bodies_overlap")


# -- drawing scenarios ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class MapSites:
    """Where base stations may stand on a map: cells of its largest free region and their clearance."""

    omap: OccupancyMap
    rows: np.ndarray
    cols: np.ndarray
    clear: np.ndarray


@cache
def map_sites(name: str) -> MapSites:
    """The cells of the map's largest 4-connected free region, with their clearance (cached per map)."""
    omap = load_builtin_map(name)
    labels, n = ndimage.label(omap.free, structure=ndimage.generate_binary_structure(2, 1))
    sizes = np.bincount(labels.ravel(), minlength=n + 1)
    sizes[0] = 0
    rows, cols = np.nonzero(labels == int(np.argmax(sizes)))
    return MapSites(omap, rows, cols, clearance(omap)[rows, cols])


def scenario_rng(seed: int, index: int) -> np.random.Generator:
    """The generator of scenario ``index``: the ``index``-th child of ``numpy.random.default_rng(seed)``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index,)))


def _uniform(rng: np.random.Generator, lo: float, hi: float, digits: int = 3) -> float:
    return round(float(rng.uniform(lo, hi)), digits)


def _place_bases(rng: np.random.Generator, sites: MapSites, n: int, min_clear: float, min_gap: float
                 ) -> list[tuple[float, float]]:
    """Up to ``n`` random points with clearance at least ``min_clear``, at least ``min_gap`` apart."""
    ok = np.flatnonzero(sites.clear >= min_clear)
    if len(ok) == 0:
        ok = np.flatnonzero(sites.clear >= 0.5 * min_clear)
    omap, res = sites.omap, sites.omap.resolution
    out: list[tuple[float, float]] = []
    for _ in range(50 * n):
        if len(out) == n:
            break
        k = ok[int(rng.integers(len(ok)))]
        x, y = omap.cell_centres(sites.rows[k], sites.cols[k]) + (rng.random(2) - 0.5) * 0.5 * res
        p = (round(float(x), 3), round(float(y), 3))
        if all(math.dist(p, q) >= min_gap for q in out):
            out.append(p)
    return out


def _robot(rng: np.random.Generator) -> str | dict[str, Any]:
    """A router: mostly the Bebot, sometimes given field by field."""
    if rng.random() < 0.8:
        return "bebot"
    return {"radius": _uniform(rng, 0.03, 0.08), "max_speed": _uniform(rng, 0.1, 0.4),
            "sensor_beams": int(rng.integers(6, 17)), "sensor_range": _uniform(rng, 0.1, 0.4)}


def _algorithm_params(rng: np.random.Generator, name: str) -> dict[str, Any]:
    """Sensible parameter choices of each registered algorithm (an unknown one runs on its defaults)."""
    triangular = str(rng.choice(["none", "local", "global"]))
    if name == "self-spreading":
        return {"triangular": triangular, "loss_margin": _uniform(rng, 0.05, 0.15),
                "turn_noise": _uniform(rng, 0.3, 2.0), "give_up_steps": int(rng.integers(5, 41))}
    if name == "agent-assisted":
        return {"triangular": triangular, "explorer": str(rng.choice(["random", "frontier"])),
                "loss_margin": _uniform(rng, 0.05, 0.15), "turn_noise": _uniform(rng, 0.2, 1.0),
                "avoid_range": _uniform(rng, 0.3, 1.0), "give_up_steps": int(rng.integers(5, 41)),
                "release_gap": _uniform(rng, 0.0, 0.05)}
    if name == "dssa":
        return {"sensing_radius_factor": _uniform(rng, 0.3, 1.0), "obstacle_forces": bool(rng.random() < 0.5),
                "obstacle_gain": _uniform(rng, 0.5, 2.0), "stable_steps": int(rng.integers(10, 41))}
    if name == "potential-field":
        return {"connectivity_k": int(rng.integers(0, 3)), "obstacle_forces": bool(rng.random() < 0.5),
                "safety_factor": _uniform(rng, 0.6, 1.0), "sensing_radius_factor": _uniform(rng, 0.3, 1.0)}
    return {}


def _radio(rng: np.random.Generator, r_c: float) -> dict[str, Any]:
    """A radio model from the registry; path-loss models sometimes with or without shadowing and packet loss."""
    models = sorted(MEDIA)
    weights = np.array([3.0 if m == "unit-disk" else 2.0 if m == "multi-wall" else 1.0 for m in models])
    model = str(rng.choice(models, p=weights / weights.sum()))
    radio: dict[str, Any] = {"model": model, "r_c": r_c}
    cls = MEDIA[model]
    if cls.uses_shadowing:
        u = rng.random()
        if u < 0.3:
            radio["shadowing_db"] = 0.0
        elif u < 0.6:
            radio["shadowing_db"] = _uniform(rng, 1.0, 6.0, 2)
    if rng.random() < (0.15 if cls.uses_shadowing else 0.05):
        radio["packet_loss"] = True
    if cls.uses_walls and rng.random() < 0.3:
        radio["wall_db"] = float(rng.choice([3.4, 6.9, 10.0]))
    return radio


def draw_scenario(seed: int, index: int, max_time: float = 60.0) -> tuple[dict[str, Any], int]:
    """Scenario ``index`` of the soak with ``seed``, as a dict, and the seed of its run.

    Args:
        seed: The soak's seed.
        index: The scenario's number.
        max_time: Longest simulated time limit (s); each scenario draws its own between 3 s and this.
    """
    rng = scenario_rng(seed, index)
    map_name = str(rng.choice(list(BUILTIN_MAPS)))
    algorithm = str(rng.choice(sorted(ALGORITHMS)))
    small = map_name in SMALL_MAPS
    r_c = _uniform(rng, 0.8, 2.0, 2) if small else _uniform(rng, 1.5, 8.0, 2)
    agents = algorithm == "agent-assisted"
    n_bases = int(rng.integers(1, 5))
    region_side = (0.8, 2.0) if agents else (0.5, 2.0)
    bases = _place_bases(rng, map_sites(map_name), n_bases, min_clear=0.6 if agents else 0.3,
                         min_gap=min(1.0, r_c))
    stations = [{"x": x, "y": y, "region": [_uniform(rng, *region_side, 2), _uniform(rng, *region_side, 2)]}
                for x, y in bases]
    routers: dict[str, Any] = {"count": 0, "robot": _robot(rng)}
    if not agents:
        # about as many as fit into the start regions (part of each is wall or beyond the start range)
        room = sum(min(s["region"][0], 1.9 * r_c) * min(s["region"][1], 1.9 * r_c) for s in stations)
        routers["count"] = int(rng.integers(3, max(4, min(80, int(15 * room)) + 1)))
        if algorithm in ("dssa", "potential-field") and rng.random() < 0.15:
            routers["start"] = "uniform"
    scenario: dict[str, Any] = {
        "name": f"soak-{seed}-{index}",
        "map": map_name,
        "algorithm": {"name": algorithm, "params": _algorithm_params(rng, algorithm)},
        "radio": _radio(rng, r_c),
        "base_stations": stations,
        "routers": routers,
        "sim": {
            "dt": float(rng.choice([0.05, 0.1, 0.2], p=[0.2, 0.6, 0.2])),
            "time_limit": _uniform(rng, 3.0, max(3.0, max_time), 1),
            "record_every": int(rng.integers(5, 21)),
            "robot_collisions": bool(rng.random() < 0.9),
        },
    }
    if agents:
        carried = None if rng.random() < 0.7 else int(rng.integers(3, 31))
        scenario["agents"] = {"per_base": int(rng.integers(1, 4)), "routers_carried": carried}
    if scenario["radio"]["model"] == "unit-disk" and small and rng.random() < 0.15:
        scenario["sim"]["coverage_method"] = "exact"
    run_seed = int(rng.integers(0, 2**31))
    return scenario, run_seed


# -- invariants ----------------------------------------------------------------------------------------------------
def wall_depth(omap: OccupancyMap, xy: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """How far each body reaches into a blocked cell (<= 0: it does not), measured exactly to the cell's square.

    Blocked cells are occupied and unknown cells and everything off the map. For each robot every blocked cell
    within ``radius + 1`` cells of its centre's cell is tested with the exact point-to-square distance.
    """
    res = omap.resolution
    ox, oy = omap.origin
    out = np.full(len(xy), -np.inf)
    if len(xy) == 0:
        return out
    ks = np.ceil(radius / res).astype(np.int64) + 1
    pad = int(ks.max())
    blocked = np.pad(omap.blocked, pad, constant_values=True)
    rows, cols = omap.world_to_cell(xy)
    rows = np.clip(rows, -pad, omap.shape[0] + pad - 1)
    cols = np.clip(cols, -pad, omap.shape[1] + pad - 1)
    for k in np.unique(ks):
        who = np.flatnonzero(ks == k)
        off = np.arange(-k, k + 1)
        rr = rows[who, None, None] + off[None, :, None]  # (m, w, 1)
        cc = cols[who, None, None] + off[None, None, :]  # (m, 1, w)
        rr_p = np.clip(rr + pad, 0, blocked.shape[0] - 1)
        cc_p = np.clip(cc + pad, 0, blocked.shape[1] - 1)
        hit = blocked[rr_p, cc_p]  # (m, w, w)
        px, py = xy[who, 0, None, None], xy[who, 1, None, None]
        x0, y0 = ox + cc * res, oy + rr * res
        dx = np.maximum(np.maximum(x0 - px, px - (x0 + res)), 0.0)
        dy = np.maximum(np.maximum(y0 - py, py - (y0 + res)), 0.0)
        dist = np.where(hit, np.hypot(dx, dy), np.inf).reshape(len(who), -1).min(axis=1)
        out[who] = radius[who] - dist
    return out


@dataclass
class Finding:
    """One kind of violation in one run: how often it was seen, when first, the worst value and an example."""

    kind: str
    known: bool
    first_step: int
    count: int = 1
    worst: float = 0.0
    example: str = ""

    def to_dict(self) -> dict[str, Any]:
        """Plain data for the report."""
        return {"kind": self.kind, "known": self.known, "first_step": self.first_step, "count": self.count,
                "worst": self.worst, "example": self.example}


class Checker:
    """Checks a running :class:`Simulation` against the invariants, with the map and the table only.

    Args:
        sim: The run.
        scenario: The scenario as plain data (which invariants apply).
    """

    def __init__(self, sim: Simulation, scenario: dict[str, Any]) -> None:
        self.sim = sim
        radio = sim.scenario.radio
        budget = radio.link_budget()
        self.noisy_radio = budget.shadowing_db > 0 or radio.packet_loss
        self.check_routers = scenario["algorithm"]["name"] in ("self-spreading", "agent-assisted")
        self.agents_promised = (radio.model == "unit-disk" and not radio.packet_loss
                                and sim.scenario.agents.routers_carried is None)
        self.collisions = sim.scenario.sim.robot_collisions
        self.reachable = sim.world.reachable
        self.findings: dict[str, Finding] = {}

    def note(self, kind: str, step: int, worst: float, example: str, known: bool = False) -> None:
        """Record a violation of ``kind`` seen at ``step`` (``worst``: larger is worse).

        A geometric violation before the first step is the start placement's, and is told apart by ``_at_start``.
        """
        if step == 0 and kind in GEOMETRIC_KINDS:
            kind += "_at_start"
        f = self.findings.get(kind)
        if f is None:
            self.findings[kind] = Finding(kind, known, step, 1, worst, example)
            return
        f.count += 1
        if worst > f.worst:
            f.worst, f.example = worst, example

    def geometry(self) -> None:
        """Centres finite, in free reachable cells; bodies clear of walls and of each other."""
        sim, step = self.sim, self.sim.steps
        sw, omap = sim.swarm, sim.world.omap
        xy = sw.xy
        finite = np.isfinite(xy).all(axis=1)
        if not finite.all():
            i = int(np.flatnonzero(~finite)[0])
            self.note("not_finite", step, float(np.count_nonzero(~finite)), f"robot {i} at {xy[i].tolist()}")
            xy, radius = xy[finite], sw.radius[finite]
        else:
            radius = sw.radius
        free = omap.is_free(xy)
        if not free.all():
            i = int(np.flatnonzero(~free)[0])
            self.note("centre_not_free", step, float(np.count_nonzero(~free)),
                      f"robot {i} (role {int(sw.role[i])}) at ({xy[i, 0]:.6f}, {xy[i, 1]:.6f})")
        rows, cols = omap.world_to_cell(xy[free])
        reach = self.reachable[rows, cols]
        if not reach.all():
            i = int(np.flatnonzero(free)[np.flatnonzero(~reach)[0]])
            self.note("centre_unreachable", step, float(np.count_nonzero(~reach)),
                      f"robot {i} at ({xy[i, 0]:.6f}, {xy[i, 1]:.6f})")
        depth = wall_depth(omap, xy, radius)
        worst = int(np.argmax(depth))
        if depth[worst] > GEOMETRY_TOL:
            self.note("body_in_wall", step, float(depth[worst]),
                      f"robot {worst} (role {int(sw.role[worst])}, state {int(sw.state[worst])}, radius "
                      f"{radius[worst]:g}) at ({xy[worst, 0]:.6f}, {xy[worst, 1]:.6f}) reaches "
                      f"{depth[worst] * 1e3:.3f} mm into a wall; {int(np.count_nonzero(depth > GEOMETRY_TOL))} "
                      "bodies in walls")
        if self.collisions and len(xy) > 1:
            tree = cKDTree(xy)
            pairs = tree.query_pairs(2.0 * float(radius.max()), output_type="ndarray")
            if len(pairs):
                gap = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1)
                over = radius[pairs[:, 0]] + radius[pairs[:, 1]] - gap
                bad = over > GEOMETRY_TOL
                if bad.any():
                    k = int(np.argmax(over))
                    i, j = (int(v) for v in pairs[k])
                    self.note("bodies_overlap", step, float(over[k]),
                              f"{int(np.count_nonzero(bad))} pairs overlap ({int(np.count_nonzero(gap == 0.0))} "
                              f"at identical coordinates); worst: robots {i} and {j} (roles {int(sw.role[i])}, "
                              f"{int(sw.role[j])}) at ({xy[i, 0]:.6f}, {xy[i, 1]:.6f}) overlap by "
                              f"{over[k] * 1e3:.3f} mm; {len(xy)} robots")

    def network(self) -> None:
        """Deployed routers have a path to a base; agents are connected (where the algorithms promise it)."""
        sim, step = self.sim, self.sim.steps
        sw, table = sim.swarm, sim.table
        if self.check_routers:
            deployed = sw.deployed
            linked = connected_to(table, sim.bases, deployed)
            cut = deployed & ~linked & (sw.role == Role.ROUTER)
            if cut.any():
                i = int(np.flatnonzero(cut)[0])
                self.note("router_cut_off", step, float(np.count_nonzero(cut)),
                          f"{int(np.count_nonzero(cut))} deployed routers without a path to a base, e.g. robot {i} "
                          f"at ({sw.xy[i, 0]:.4f}, {sw.xy[i, 1]:.4f})", known=self.noisy_radio)
        if len(sim.agents):
            linked = agents_connected(table, sim.agents, sim.bases, sw.role != Role.AGENT)
            if not linked.all():
                i = int(sim.agents[np.flatnonzero(~linked)[0]])
                self.note("agents_disconnected", step, float(np.count_nonzero(~linked)),
                          f"{int(np.count_nonzero(~linked))} of {len(linked)} agents cut off, e.g. robot {i} at "
                          f"({sw.xy[i, 0]:.4f}, {sw.xy[i, 1]:.4f})", known=not self.agents_promised)

    def coverage(self) -> None:
        """``0 <= connected coverage <= coverage <= 1``."""
        m = self.sim.metrics()
        cov, con = m.coverage, m.connected_coverage
        if not (0.0 <= con <= cov + 1e-12 and 0.0 <= cov <= 1.0 + 1e-12):
            self.note("coverage_range", self.sim.steps, 1.0, f"coverage {cov!r}, connected coverage {con!r}")


@dataclass
class RunOutcome:
    """What one checked run did."""

    steps: int
    robots: int
    state: bytes
    stop: str


def run_checked(scenario: dict[str, Any], run_seed: int, checker_out: list[Checker] | None = None) -> RunOutcome:
    """Run ``scenario`` with ``run_seed`` to its time limit (or until nothing moves), checking the invariants.

    Geometry is checked about 60 times per run, connectivity at every step, coverage at the start, about 6
    times (twice under a path-loss radio) and at the end. The run's final positions, headings, states and
    statuses come back as bytes (for determinism).
    """
    sc = load_scenario(scenario)
    sim = Simulation(sc, run_seed)
    checker = Checker(sim, scenario)
    if checker_out is not None:
        checker_out.append(checker)
    max_steps = max(1, round(sc.sim.time_limit / sc.sim.dt))
    geo_every = max(1, max_steps // 60)
    # coverage under a path-loss radio is decided cell by cell through walls: costly, so less often
    cov_every = max(1, max_steps // (6 if sc.radio.model == "unit-disk" else 2))
    checker.geometry()
    checker.network()
    checker.coverage()
    stop = "time_limit"
    while sim.steps < max_steps:
        sim.step()
        checker.network()
        if sim.steps % geo_every == 0:
            checker.geometry()
        if sim.steps % cov_every == 0:
            checker.coverage()
        if sc.sim.stop_when_settled and not sim.controller.unsettled().any():
            stop = "settled"
            break
    checker.geometry()
    checker.coverage()
    sw = sim.swarm
    state = b"".join(np.ascontiguousarray(a).tobytes() for a in (sw.xy, sw.heading, sw.state, sw.status, sw.role))
    return RunOutcome(sim.steps, len(sw), state, stop)


def soak_one(seed: int, index: int, max_time: float, determinism: bool) -> dict[str, Any]:
    """Draw, run and check scenario ``index``; the result as plain data (never raises)."""
    t0 = time.perf_counter()
    out: dict[str, Any] = {"index": index, "outcome": "ok", "findings": []}
    try:
        scenario, run_seed = draw_scenario(seed, index, max_time)
        out.update(map=scenario["map"], algorithm=scenario["algorithm"]["name"], radio=scenario["radio"]["model"],
                   run_seed=run_seed)
        checkers: list[Checker] = []
        try:
            first = run_checked(scenario, run_seed, checkers)
        except ScenarioError as exc:
            if checkers:  # the run had started: a ScenarioError mid-run is a crash
                raise
            out.update(outcome="refused", error=str(exc))
            return out
        out.update(steps=first.steps, robots=first.robots, stop=first.stop,
                   findings=[f.to_dict() for f in checkers[0].findings.values()])
        if determinism:
            second = run_checked(scenario, run_seed)
            out["determinism_checked"] = True
            if second.state != first.state or second.steps != first.steps:
                out["findings"].append(Finding("nondeterministic", False, second.steps,
                                               example=f"second run: {second.steps} steps, {second.robots} robots; "
                                               f"first: {first.steps} steps, {first.robots} robots").to_dict())
    except Exception as exc:  # a crash is a result of the soak, not the end of it
        out.update(outcome="crash", error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
    finally:
        out["wall_s"] = round(time.perf_counter() - t0, 3)
    return out


# -- workers -------------------------------------------------------------------------------------------------------
def _worker(conn: Connection) -> None:
    """Run the tasks sent on ``conn`` until it sends ``None``."""
    while True:
        task = conn.recv()
        if task is None:
            return
        conn.send(soak_one(*task))


@dataclass
class Worker:
    """A worker process and the task it is running."""

    proc: mp.Process
    conn: Connection
    index: int | None = None
    started: float = 0.0
    limit: float = 0.0


def _spawn(ctx: Any) -> Worker:
    parent, child = ctx.Pipe()
    proc = ctx.Process(target=_worker, args=(child,), daemon=True)
    proc.start()
    child.close()
    return Worker(proc, parent)


def _stop(worker: Worker) -> None:
    worker.proc.kill()
    worker.proc.join()
    worker.conn.close()


def _lost(seed: int, index: int, max_time: float, outcome: str, error: str) -> dict[str, Any]:
    """The result of a scenario whose worker hung or died (what it was, drawn again here)."""
    scenario, run_seed = draw_scenario(seed, index, max_time)
    return {"index": index, "outcome": outcome, "error": error, "findings": [], "map": scenario["map"],
            "algorithm": scenario["algorithm"]["name"], "radio": scenario["radio"]["model"], "run_seed": run_seed}


def soak(seed: int, indices: list[int], max_time: float, jobs: int, timeout: float, det_every: int,
         on_result: Any) -> tuple[list[dict[str, Any]], bool]:
    """Run the scenarios ``indices`` on ``jobs`` worker processes, killing a worker that runs past ``timeout``.

    Returns:
        The results in the order they came, and whether the soak was interrupted (SIGINT or SIGTERM to this
        process) before all were done; the workers are stopped either way.
    """
    ctx = mp.get_context("spawn")
    pending = list(reversed(indices))
    workers = [_spawn(ctx) for _ in range(max(1, min(jobs, len(indices))))]
    results: list[dict[str, Any]] = []
    interrupted = False

    def finish(result: dict[str, Any]) -> None:
        results.append(result)
        on_result(result)

    def terminate(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        while pending or any(w.index is not None for w in workers):
            for w in workers:
                if w.index is None and pending:
                    i = pending.pop()
                    det = det_every > 0 and i % det_every == 0
                    w.conn.send((seed, i, max_time, det))
                    w.index, w.started, w.limit = i, time.monotonic(), timeout * (2 if det else 1)
            busy = [w for w in workers if w.index is not None]
            now = time.monotonic()
            left = min(w.started + w.limit - now for w in busy)
            ready = wait([w.conn for w in busy], timeout=max(0.0, left))
            for k, w in enumerate(workers):
                if w.index is None:
                    continue
                if w.conn in ready:
                    try:
                        result = w.conn.recv()
                    except (EOFError, OSError):
                        w.proc.join(5)
                        finish(_lost(seed, w.index, max_time, "worker_died", f"worker exit code {w.proc.exitcode}"))
                        _stop(w)
                        workers[k] = _spawn(ctx)
                        continue
                    w.index = None
                    finish(result)
                elif time.monotonic() - w.started > w.limit:
                    finish({**_lost(seed, w.index, max_time, "hang", f"no result after {w.limit:g} s of wall time; "
                                    "killed"), "wall_s": round(time.monotonic() - w.started, 3)})
                    _stop(w)
                    workers[k] = _spawn(ctx)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        signal.signal(signal.SIGTERM, previous)
        for w in workers:
            if w.proc.is_alive() and w.index is None:
                try:
                    w.conn.send(None)
                except OSError:
                    pass
                w.proc.join(2)
            _stop(w)
    return results, interrupted


# -- reporting -----------------------------------------------------------------------------------------------------
def replay_command(seed: int, index: int, max_time: float) -> str:
    """The command that replays scenario ``index`` of the soak with ``seed``."""
    python = Path(sys.executable)
    try:
        python = python.relative_to(Path.cwd())
    except ValueError:
        pass
    script = Path(__file__).resolve()
    try:
        script = script.relative_to(Path.cwd())
    except ValueError:
        pass
    limit = "" if max_time == 60.0 else f" --time-limit {max_time:g}"
    return f"{python} {script} --replay {index} --seed {seed}{limit}"


def failing(result: dict[str, Any]) -> list[str]:
    """The reasons a result is a failure (empty: it is not)."""
    reasons = [result["outcome"]] if result["outcome"] in FAILURE_KINDS else []
    reasons += [f["kind"] for f in result["findings"] if not f["known"]]
    return reasons


def describe(result: dict[str, Any]) -> str:
    """One or a few lines saying what went wrong in a result."""
    what = f"#{result['index']} {result.get('map', '?')} {result.get('algorithm', '?')} {result.get('radio', '?')}"
    lines = [what + f": {result['outcome']}"]
    if result.get("error"):
        lines.append(f"    {result['error']}")
    for f in result["findings"]:
        tag = "known " if f["known"] else ""
        lines.append(f"    {tag}{f['kind']} (first at step {f['first_step']}, seen at {f['count']} checks, "
                     f"worst {f['worst']:.3g}): {f['example']}")
    return "\n".join(lines)


def summarize(results: list[dict[str, Any]], wall: float) -> dict[str, Any]:
    """Counts of outcomes and violations."""
    outcomes = Counter(r["outcome"] for r in results)
    violations: Counter[str] = Counter()
    known: Counter[str] = Counter()
    for r in results:
        for f in r["findings"]:
            (known if f["known"] else violations)[f["kind"]] += 1
    failed = [r["index"] for r in results if failing(r)]
    return {
        "count": len(results),
        "ran": outcomes["ok"],
        "refused": outcomes["refused"],
        "crashes": outcomes["crash"] + outcomes["worker_died"],
        "hangs": outcomes["hang"],
        "violations": dict(sorted(violations.items())),
        "known_violations": dict(sorted(known.items())),
        "determinism_checked": sum(1 for r in results if r.get("determinism_checked")),
        "failed_scenarios": len(failed),
        "wall_time_s": round(wall, 1),
        "scenario_wall_s_max": max((r.get("wall_s", 0.0) for r in results), default=0.0),
        "by_algorithm": dict(sorted(Counter(r.get("algorithm", "?") for r in results).items())),
        "by_map": dict(sorted(Counter(r.get("map", "?") for r in results).items())),
        "by_radio": dict(sorted(Counter(r.get("radio", "?") for r in results).items())),
    }


def print_summary(s: dict[str, Any]) -> None:
    """Print the summary block."""
    print(f"\nsoak: {s['count']} scenarios ({s['ran']} ran, {s['refused']} refused), {s['crashes']} crashes, "
          f"{s['hangs']} hangs, {s['failed_scenarios']} failed; determinism checked on {s['determinism_checked']}; "
          f"wall time {s['wall_time_s']:.1f} s (slowest scenario {s['scenario_wall_s_max']:.1f} s)")
    print("violations (scenarios): " + (", ".join(f"{k} {v}" for k, v in s["violations"].items()) or "none"))
    print("known, not failures (scenarios): "
          + (", ".join(f"{k} {v}" for k, v in s["known_violations"].items()) or "none"))
    for key in ("by_algorithm", "by_map", "by_radio"):
        print(f"{key.replace('_', ' ')}: " + ", ".join(f"{k} {v}" for k, v in s[key].items()))


def _code_version() -> str:
    """The commit the soak ran on, with ``+dirty`` when the work tree differs from it ('' outside git)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""
    return head + ("+dirty" if head and dirty else "")


def replay(seed: int, index: int, max_time: float, yaml_path: str | None) -> int:
    """Rebuild scenario ``index``, print it as YAML, run it (twice, for determinism) and print what fails."""
    scenario, run_seed = draw_scenario(seed, index, max_time)
    text = yaml.safe_dump(scenario, sort_keys=False)
    print(f"# scenario {index} of the soak with seed {seed}; run seed {run_seed}\n{text}")
    if yaml_path:
        Path(yaml_path).write_text(text, encoding="utf-8")
        print(f"wrote {yaml_path}; to run the scenario with amronet (which also stops at a coverage target and "
              f"checks none of these invariants): amronet run {yaml_path} --seed {run_seed} --out OUT\n")
    result = soak_one(seed, index, max_time, determinism=True)
    print(describe(result))
    if result.get("traceback"):
        print(result["traceback"])
    print(f"steps {result.get('steps')}, robots at the end {result.get('robots')}, stop {result.get('stop')}, "
          f"wall {result.get('wall_s')} s")
    return 1 if failing(result) else 0


def main(argv: list[str] | None = None) -> int:
    """Command line: a soak of ``--count`` scenarios, or ``--replay`` of one."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--count", type=int, default=100, help="scenarios to draw and run (default 100)")
    p.add_argument("--seed", type=int, default=1, help="the soak's seed (default 1)")
    p.add_argument("--start", type=int, default=0, help="number of the first scenario (default 0)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--time-limit", type=float, default=60.0,
                   help="longest simulated time of a scenario in seconds; each draws its own from 3 s up (default 60)")
    p.add_argument("--timeout", type=float, default=300.0,
                   help="wall seconds after which a scenario counts as hung and its worker is killed (default 300; "
                        "doubled for a determinism check)")
    p.add_argument("--determinism-every", type=int, default=10,
                   help="run every N-th scenario twice and compare bit for bit (default 10; 0: never)")
    p.add_argument("--out", help="write the report (summary and every scenario's result) to this JSON file")
    p.add_argument("--replay", type=int, metavar="INDEX", help="rebuild and run scenario INDEX in this process")
    p.add_argument("--yaml", help="with --replay: also write the scenario to this YAML file")
    args = p.parse_args(argv)
    if args.time_limit < 3.0 or not math.isfinite(args.time_limit):
        p.error("--time-limit must be at least 3 seconds")
    if args.replay is not None:
        return replay(args.seed, args.replay, args.time_limit, args.yaml)
    if args.count < 1 or args.jobs < 1 or args.start < 0:
        p.error("--count and --jobs must be at least 1, --start at least 0")
    indices = list(range(args.start, args.start + args.count))
    done = 0
    t0 = time.perf_counter()

    def on_result(result: dict[str, Any]) -> None:
        nonlocal done
        done += 1
        reasons = failing(result)
        if reasons:
            print(f"FAIL {describe(result)}\n    replay: {replay_command(args.seed, result['index'], args.time_limit)}",
                  flush=True)
        if done % 25 == 0 or done == len(indices):
            print(f"[{done}/{len(indices)}] {time.perf_counter() - t0:.0f} s", flush=True)

    results, interrupted = soak(args.seed, indices, args.time_limit, args.jobs, args.timeout,
                                args.determinism_every, on_result)
    results.sort(key=lambda r: r["index"])
    summary = summarize(results, time.perf_counter() - t0)
    summary.update(seed=args.seed, start=args.start, asked=args.count, interrupted=interrupted,
                   time_limit=args.time_limit, timeout=args.timeout, jobs=args.jobs, code=_code_version())
    if interrupted:
        print(f"\ninterrupted: {len(results)} of {args.count} scenarios done (the summary counts those)")
    print_summary(summary)
    failed = [r for r in results if failing(r)]
    if failed:
        print("\nreplay the failures:")
        for r in failed:
            print(f"  {replay_command(args.seed, r['index'], args.time_limit)}   # {', '.join(failing(r))}")
    if args.out:
        Path(args.out).write_text(json.dumps({"summary": summary, "results": results}, indent=1) + "\n",
                                  encoding="utf-8")
    return 1 if failed else 0


if __name__ == "__main__":
    os.environ.setdefault("MPLBACKEND", "Agg")
    sys.exit(main())
