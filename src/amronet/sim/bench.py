"""``amronet bench``: robot-steps per second of an algorithm's full step on a real map.

The benchmark keeps the floor plan of the chosen map but scales it up (coarser metres per cell, same cells)
until every robot has ``area_per_robot`` square metres of reachable free space, so that 100 000 disc robots fit
physically; with ``r_c`` = 1 m and the default 0.25 m² per robot a node hears about a dozen others. Routers are
scattered uniformly over the reachable free space (``routers.start: uniform``) with one base station per
1 000 robots, and the loop runs the full step — sensing, decision, motion with collision checks, radio medium —
for ``steps`` steps after one warm-up step (numba compilation is cached on disk, so only the first ever run
pays it). Metrics (coverage) are not part of the timed step. From :data:`amronet.threads.MIN_ITEMS` robots on, the
neighbour search and the sensing, deciding and planning of the moves run on every core numba has (``threads`` in
the report; ``NUMBA_NUM_THREADS=1`` keeps them on one).
"""

from __future__ import annotations

import dataclasses
import math
import platform
import time
from typing import Any

import numpy as np
from scipy import ndimage

from amronet import limits
from amronet.engine.robots import Role
from amronet.errors import AmronetError, ScenarioError
from amronet.scenario import load_scenario
from amronet.sim.loop import StepKind, check_seed
from amronet.sim.simulation import Simulation
from amronet.threads import threads_for
from amronet.version import __version__
from amronet.world.builtin import resolve_map
from amronet.world.space import clearance

__all__ = ["run_bench"]

BASE_CLEARANCE_M = 0.3
"""Base stations go where the nearest obstacle is at least this far (a reference node's body is 0.165 m)."""

BASE_SPACING_M = 2.0 * BASE_CLEARANCE_M
"""And at least this far from each other (their reference nodes' bodies must not overlap)."""


def _largest_free_region(omap) -> np.ndarray:
    """Mask of the largest 4-connected free region of the map (where the benchmark's robots live)."""
    labels, count = ndimage.label(omap.free)
    if count == 0:
        raise ValueError(f"map {omap.name!r} has no free cell")
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return labels == int(np.argmax(sizes))


def _spaced_bases(omap, rows: np.ndarray, cols: np.ndarray, n_bases: int, rng: np.random.Generator) -> np.ndarray:
    """``n_bases`` cell centres among ``rows, cols``, drawn at random, every two at least ``BASE_SPACING_M`` apart.

    The first draw is kept where it is spaced enough (so that a draw without a clash is the one it always was);
    a base too close to an earlier one is drawn again.

    Raises:
        AmronetError: The cells cannot hold that many bases that far apart (too many robots for the map).
    """
    pick = rng.choice(len(rows), size=min(n_bases, len(rows)), replace=False)
    kept: list[np.ndarray] = []
    candidates = iter(omap.cell_centres(rows[pick], cols[pick]))
    for _ in range(n_bases + 100 * n_bases):
        xy = next(candidates, None)
        if xy is None:  # a clash: another cell, at random
            k = int(rng.integers(len(rows)))
            xy = omap.cell_centres(rows[k], cols[k])
        if all(math.dist(xy, other) >= BASE_SPACING_M for other in kept):
            kept.append(xy)
            if len(kept) == n_bases:
                return np.array(kept)
    raise AmronetError(f"--robots: the map has no room for {n_bases} base stations {BASE_SPACING_M} m apart "
                       "(one per 1 000 robots); use fewer robots")


def run_bench(
    algorithm: str = "self-spreading",
    robots: int = 3000,
    steps: int = 500,
    map_name: str = "hospital_section",
    seed: int = 0,
    r_c: float = 1.0,
    area_per_robot: float = 0.25,
    force: bool = False,
    step: StepKind = "compiled",
    stretches: bool = False,
) -> dict[str, Any]:
    """Time ``steps`` full steps of ``robots`` robots and return a report (robot-steps per second and more).

    Before the map is scaled or a robot placed, the resource guard (:mod:`amronet.limits`) estimates the memory
    (``BYTES_PER_ROBOT`` per robot, ``BYTES_PER_LINK`` per link at the density the benchmark sets up) and the work
    (robots times steps, the warm-up step included). ``step`` picks the loop's step (``compiled`` or the
    phase-by-phase ``reference``, see :class:`~amronet.sim.loop.Loop`): both give the same robots bit for bit.
    ``stretches``: time the steps as a run takes those between two records (:meth:`~amronet.sim.loop.Loop.advance`:
    in compiled stretches where the fast step can), not one :meth:`~amronet.sim.loop.Loop.step` call per step; the
    same robots bit for bit.

    Raises:
        AmronetError: ``robots`` or ``steps`` below 1, ``r_c`` not a finite number > 0, more robots than the
            memory available holds, or (without ``force``) more than ``limits.MAX_ROBOT_STEPS`` robot-steps (named
            as the options of ``amronet bench``); an ``r_c`` too short for the routers' step, or an algorithm
            whose agents release the routers.
        ScenarioError: ``seed`` is not an integer in ``[0, 2**63 - 1]`` (as ``amronet run`` refuses it).
    """
    seed = check_seed(seed)
    for option, value in (("--robots", robots), ("--steps", steps)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise AmronetError(f"{option}: must be a whole number >= 1, got {value!r}")
    if isinstance(r_c, bool) or not math.isfinite(r_c) or r_c <= 0:
        raise AmronetError(f"--rc: must be a finite number > 0, got {r_c!r}")
    degree = min(math.pi * r_c**2 / area_per_robot, robots - 1.0)  # the density the scaled map gives
    limits.check_memory(robots * (limits.BYTES_PER_ROBOT + degree * limits.BYTES_PER_LINK), "--robots",
                        f"{robots} robots", "use fewer robots", error=AmronetError)
    limits.check_work(robots * (steps + 1), limits.MAX_ROBOT_STEPS, "--robots",
                      f"{robots} robots x {steps + 1} steps = {limits.format_count(robots * (steps + 1))} robot-steps",
                      "use fewer robots or steps", force, error=AmronetError)
    omap = resolve_map(map_name)
    rng = np.random.default_rng(seed)
    largest = _largest_free_region(omap)
    area = np.count_nonzero(largest) * omap.resolution**2
    scale = max(1.0, math.sqrt(robots * area_per_robot / max(area, 1e-9)))
    if scale > 1.0:
        omap = dataclasses.replace(omap, resolution=omap.resolution * scale, _cache={})
    roomy = largest & (clearance(omap) >= BASE_CLEARANCE_M)  # room for a base node's body
    rows, cols = np.nonzero(roomy if roomy.any() else largest)
    bases = _spaced_bases(omap, rows, cols, max(1, robots // 1000), rng)
    n_bases = len(bases)
    scenario = load_scenario({
        "name": f"bench-{map_name}-{robots}",
        "map": map_name,
        "algorithm": {"name": algorithm},
        "radio": {"r_c": r_c},
        "base_stations": [{"x": float(x), "y": float(y)} for x, y in bases],
        "routers": {"count": robots, "start": "uniform"},
        "sim": {"time_limit": 1e9, "stop_when_settled": False},
    })
    t0 = time.perf_counter()
    # the work is checked above; time_limit is a sentinel
    try:
        sim = Simulation(scenario, seed, omap=omap, force=True, step=step)
    except ScenarioError as exc:  # fields bench does not have, said as its own options
        if exc.field == "algorithm.params.loss_margin":  # the band is a share of r_c
            why = exc.message.split(";")[0]
            raise AmronetError(f"--rc: {r_c:g} m is too short: {why}; give a larger --rc") from None
        if exc.field not in ("routers.count", "agents.per_base"):
            raise
        raise AmronetError(f"--algorithm: bench times routers that spread by themselves; in {algorithm} agents "
                           "release them: time a run instead (amronet run, e.g. --preset agent-assisted-office)"
                           ) from None
    setup_s = time.perf_counter() - t0
    sim.step()  # warm-up (numba compilation from cache, first allocations)
    for k in sim.phase_seconds:
        sim.phase_seconds[k] = 0.0
    t0 = time.perf_counter()
    if stretches:
        sim.advance(steps)
    else:
        for _ in range(steps):
            sim.step()
    wall = time.perf_counter() - t0
    n = int(np.count_nonzero(sim.swarm.role == Role.ROUTER))
    t1 = time.perf_counter()
    cov = sim.metrics()
    metrics_s = time.perf_counter() - t1
    return {
        "algorithm": algorithm,
        "step": step,
        "map": map_name,
        "map_scale": round(scale, 3),
        "robots": n,
        "base_stations": n_bases,
        "steps": steps,
        "stretches": stretches,
        "r_c": r_c,
        "mean_degree": float(sim.table.degree.mean()),
        "setup_s": round(setup_s, 3),
        "wall_s": round(wall, 3),
        "steps_per_s": round(steps / wall, 2),
        "robot_steps_per_s": round(n * steps / wall),
        "phase_share": {k: round(v / wall, 3) for k, v in sim.phase_seconds.items()},
        "metrics_call_s": round(metrics_s, 4),
        "coverage_after": round(cov.coverage, 4),
        "routers_deployed_after": cov.routers_deployed,
        "threads": threads_for(n),
        "python": platform.python_version(),
        "amronet": __version__,
    }
