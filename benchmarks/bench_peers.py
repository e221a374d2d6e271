"""Peer benchmark: robot-steps per second of amronet's self-spreading step against Mesa at the same N.

Mesa side, in both of Mesa's continuous spaces, and amronet is judged against the faster of the two in each round:
``experimental``: N ``ContinuousSpaceAgent`` in ``mesa.experimental.continuous_space.ContinuousSpace`` (what Mesa
3.x's own boid example uses), each querying ``get_neighbors_in_radius``; ``space``: N ``mesa.Agent`` in the stable
``mesa.space.ContinuousSpace`` (what most Mesa models use), moved with ``move_agent`` and querying
``get_neighbors(pos, r_c)``. Both in a square of the same area as the free space ``amronet bench`` gives the N robots
(N x 0.25 m², or the map's free area if larger). Each agent, activated in random order (``shuffle_do``), does what a
self-spreading router does at least every step: a random-walk move (Gaussian heading noise of the same sigma, the
Bebot's 0.2 m/s x 0.1 s step, reflected at the walls of the square) and a radius query
``get_neighbors_in_radius(r_c)``. No obstacles, no sensing, no state machine, no radio model: a lower bound on the
work of amronet's step, written as a Mesa user would write it.

amronet side: :func:`amronet.sim.bench.run_bench` (``amronet bench --algorithm self-spreading``), the full step on
the scaled ``hospital_section`` floor plan, taken as a run takes the steps between two records
(:meth:`amronet.sim.loop.Loop.advance`: in compiled stretches, radio included, where they apply; the ratio is this
one's), and one :meth:`~amronet.sim.loop.Loop.step` call per step (what ``amronet bench`` times; shown beside it).
Both sides run a warm-up (numba kernels compiled or loaded from the cache first) and a short probe that sets the
number of timed steps so each measurement lasts about ``--seconds``.

Run: ``.venv/bin/pip install -e .[bench]`` then ``.venv/bin/python benchmarks/bench_peers.py`` (or
``make bench-peers``).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from typing import Any

try:
    import mesa
    from mesa.experimental.continuous_space import ContinuousSpace, ContinuousSpaceAgent
    from mesa.space import ContinuousSpace as StableContinuousSpace
except ImportError:
    print("bench_peers: Mesa is not installed; run `pip install -e .[bench]` (or `make bench-peers`)", file=sys.stderr)
    sys.exit(2)

import numpy as np
from scipy import ndimage

from amronet.sim.bench import run_bench
from amronet.world.builtin import resolve_map

SPEED = 0.2  # m/s, the Bebot default (amronet's self-spreading preset)
DT = 0.1  # s, amronet's default step
TURN_NOISE = 1.0  # rad per sqrt(s), SelfSpreadingParams.turn_noise default
AREA_PER_ROBOT = 0.25  # m², run_bench's default


def walk(model: Any, position: Any, heading: float) -> tuple[float, float, float]:
    """One random-walk move of ``model.step_len`` along ``heading``, reflected at the square's walls.

    Returns:
        The new ``(x, y, heading)``.
    """
    x, y = position
    x += model.step_len * math.cos(heading)
    y += model.step_len * math.sin(heading)
    if not 0.0 <= x <= model.side:
        x = -x if x < 0.0 else 2.0 * model.side - x
        heading = math.pi - heading
    if not 0.0 <= y <= model.side:
        y = -y if y < 0.0 else 2.0 * model.side - y
        heading = -heading
    return x, y, heading


class Walker(ContinuousSpaceAgent):
    """A random walker that looks up its neighbours within ``r_c`` every step."""

    def __init__(self, space: ContinuousSpace, model: PeerModel, position: np.ndarray, heading: float) -> None:
        super().__init__(space, model)
        self.position = position
        self.heading = heading
        self.neighbours: list[Walker] = []

    def step(self) -> None:
        """Turn by Gaussian noise, move one step (reflected at the bounds), query the neighbours in radius."""
        m = self.model
        x, y, self.heading = walk(m, self.position, self.heading + self.random.gauss(0.0, m.sigma))
        self.position = (x, y)
        self.neighbours, _ = self.get_neighbors_in_radius(radius=m.r_c)


class PeerModel(mesa.Model):
    """N walkers in a ``side`` x ``side`` continuous space (no torus)."""

    def __init__(self, n: int, side: float, r_c: float, seed: int = 0) -> None:
        super().__init__(seed=seed)
        self.side, self.r_c = side, r_c
        self.step_len, self.sigma = SPEED * DT, TURN_NOISE * math.sqrt(DT)
        self.space = ContinuousSpace([[0.0, side], [0.0, side]], torus=False, random=self.random, n_agents=n)
        for xy, heading in zip(self.rng.random((n, 2)) * side, self.rng.uniform(-math.pi, math.pi, n), strict=True):
            Walker(self.space, self, xy, float(heading))

    def step(self) -> None:
        """Activate every walker once, in random order."""
        self.agents.shuffle_do("step")


class StableWalker(mesa.Agent):
    """The same walker in Mesa's stable ``mesa.space.ContinuousSpace``."""

    def __init__(self, model: StablePeerModel, heading: float) -> None:
        super().__init__(model)
        self.heading = heading
        self.neighbours: list[StableWalker] = []

    def step(self) -> None:
        """Turn by Gaussian noise, move one step (reflected at the bounds), query the neighbours in radius."""
        m = self.model
        x, y, self.heading = walk(m, self.pos, self.heading + self.random.gauss(0.0, m.sigma))
        m.space.move_agent(self, (min(max(x, 0.0), m.side), min(max(y, 0.0), m.side)))
        self.neighbours = m.space.get_neighbors(self.pos, m.r_c, include_center=False)


class StablePeerModel(mesa.Model):
    """N walkers in Mesa's stable continuous space, ``side`` x ``side`` (no torus)."""

    def __init__(self, n: int, side: float, r_c: float, seed: int = 0) -> None:
        super().__init__(seed=seed)
        self.side, self.r_c = side, r_c
        self.step_len, self.sigma = SPEED * DT, TURN_NOISE * math.sqrt(DT)
        # x_max is exclusive in mesa.space: a hair beyond the side keeps a walker on the wall inside
        self.space = StableContinuousSpace(side + 1e-9, side + 1e-9, torus=False)
        for xy, heading in zip(self.rng.random((n, 2)) * side, self.rng.uniform(-math.pi, math.pi, n), strict=True):
            self.space.place_agent(StableWalker(self, float(heading)), (float(xy[0]), float(xy[1])))

    def step(self) -> None:
        """Activate every walker once, in random order."""
        self.agents.shuffle_do("step")


MESA_VARIANTS = {"experimental": PeerModel, "space": StablePeerModel}
"""Mesa's two continuous spaces, by the module they come from."""


def free_area(map_name: str, n: int) -> float:
    """Square metres of free space ``run_bench`` gives ``n`` robots on ``map_name`` (largest free region, scaled)."""
    omap = resolve_map(map_name)
    labels, count = ndimage.label(omap.free)
    largest = int(np.bincount(labels.ravel())[1:].max()) if count else 0
    return max(largest * omap.resolution**2, n * AREA_PER_ROBOT)


def time_steps(step: Any, steps: int) -> float:
    """Seconds that ``steps`` calls of ``step`` take."""
    t0 = time.perf_counter()
    for _ in range(steps):
        step()
    return time.perf_counter() - t0


def bench_mesa(n: int, side: float, r_c: float, seconds: float, variant: str = "experimental") -> dict[str, Any]:
    """Time a Mesa model at ``n`` agents for about ``seconds`` (after 2 warm-up steps and a 3-step probe)."""
    model = MESA_VARIANTS[variant](n, side, r_c)
    time_steps(model.step, 2)
    steps = max(3, round(seconds * 3 / time_steps(model.step, 3)))
    wall = time_steps(model.step, steps)
    degree = float(np.mean([len(a.neighbours) for a in model.agents]))
    return {"steps": steps, "wall_s": round(wall, 3), "robot_steps_per_s": round(n * steps / wall),
            "mean_degree": round(degree, 2), "mesa": mesa.__version__, "variant": variant}


def bench_amronet(n: int, map_name: str, r_c: float, seconds: float, stretches: bool = True) -> dict[str, Any]:
    """Time amronet's self-spreading step at ``n`` robots for about ``seconds`` (after a warm-up and a probe).

    ``stretches``: the steps as a run takes them between records (:meth:`amronet.sim.loop.Loop.advance`), else one
    :meth:`~amronet.sim.loop.Loop.step` call per step.
    """
    probe = run_bench(robots=n, steps=10, map_name=map_name, r_c=r_c, stretches=stretches)  # compiles kernels first
    steps = max(3, round(seconds * 10 / max(probe["wall_s"], 1e-3)))
    return run_bench(robots=n, steps=steps, map_name=map_name, r_c=r_c, stretches=stretches)


def measure(n: int, map_name: str, r_c: float, seconds: float, rounds: int) -> dict[str, Any]:
    """``rounds`` rounds at ``n``: each Mesa variant, then amronet, back to back; the ratio to the faster Mesa.

    The machines this runs on change speed by up to 2x from minute to minute, so one pair proves little: the ratio is
    taken within each pair (both sides measured under the same conditions) and the median ratio reported, with the
    lowest and highest.
    """
    side = math.sqrt(free_area(map_name, n))
    pairs = []
    for _ in range(rounds):
        variants = {v: bench_mesa(n, side, r_c, seconds, v) for v in MESA_VARIANTS}
        m = max(variants.values(), key=lambda r: r["robot_steps_per_s"])
        a = bench_amronet(n, map_name, r_c, seconds)
        one = bench_amronet(n, map_name, r_c, seconds, stretches=False)
        pairs.append({"mesa": m, "mesa_variants": variants, "amronet": a, "amronet_step_calls": one,
                      "ratio": round(a["robot_steps_per_s"] / m["robot_steps_per_s"], 1)})
    ratios = [p["ratio"] for p in pairs]
    return {"robots": n, "area_m2": round(side**2, 1), "r_c": r_c, "rounds": pairs,
            "ratio_median": round(statistics.median(ratios), 1), "ratio_min": min(ratios), "ratio_max": max(ratios)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="30,300,3000", help="comma-separated N (default 30,300,3000)")
    parser.add_argument("--map", default="hospital_section", help="amronet's floor plan (sets the area)")
    parser.add_argument("--rc", type=float, default=1.0, help="communication radius = query radius (m)")
    parser.add_argument("--seconds", type=float, default=2.0, help="target length of each measurement (s)")
    parser.add_argument("--rounds", type=int, default=3,
                        help="pairs of measurements (Mesa, then amronet) per N; the median ratio is reported "
                             "(default 3)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error(f"--rounds: must be a whole number >= 1, got {args.rounds}")
    sizes = [int(s) for s in args.sizes.split(",") if s.strip()]
    rows = [measure(n, args.map, args.rc, args.seconds, args.rounds) for n in sizes]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"Mesa {mesa.__version__} (random walk + radius query; the faster of its two continuous spaces in each "
          "round) vs amronet (full self-spreading step), "
          f"r_c = {args.rc} m, map {args.map}, {args.rounds} rounds per N (each ratio within one Mesa-amronet pair)")
    print("| N | area m² | Mesa experimental robot-steps/s | Mesa space robot-steps/s | amronet robot-steps/s | "
          "ratio per round | median ratio | amronet, one step() call per step | degree Mesa/amronet |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        pairs = r["rounds"]
        rates = {v: " / ".join(f"{p['mesa_variants'][v]['robot_steps_per_s']:,}" for p in pairs) for v in MESA_VARIANTS}
        ours = " / ".join(f"{p['amronet']['robot_steps_per_s']:,}" for p in pairs)
        calls = " / ".join(f"{p['amronet_step_calls']['robot_steps_per_s']:,}" for p in pairs)
        ratios = " / ".join(f"{p['ratio']:,.1f}x" for p in pairs)
        degrees = f"{pairs[-1]['mesa']['mean_degree']:.1f}/{pairs[-1]['amronet']['mean_degree']:.1f}"
        print(f"| {r['robots']:,} | {r['area_m2']:,.0f} | {rates['experimental']} | {rates['space']} | {ours} | "
              f"{ratios} | "
              f"**{r['ratio_median']:,.1f}x** | {calls} | {degrees} |")


if __name__ == "__main__":
    main()
