"""Escape time of the agents' explorers: how long an agent that starts in a room with one door takes to leave it.

Run: ``.venv/bin/python benchmarks/bench_escape.py [--seeds 50] [--cap 1200] [--explorers random random-escape]``.

Issue #15: with the paper's ``random`` explorer, agents that start in a room stayed in it. Each run here is an
agent-assisted run (the ``agent-assisted-office`` preset: a Pioneer agent, ``dt`` 0.1 s, 99 % coverage target) with
one base station inside a room of a built-in map and one agent (``--agents``), ``radio.r_c`` 3 m (the issue's; the
agent releases routers in the room as it goes). The run is stepped until the agent's centre leaves the room's
interior by more than :data:`CLEAR_M` (through the door, its body clear of the doorway) or ``--cap`` simulated
seconds pass. Rooms (``--rooms``), all on ``office-32x32`` with one door: ``small-office`` (2.8 m x 6.3 m, 1.0 m
door), ``office`` (4.4 m x 6.3 m, 1.2 m door), ``wide-room`` (6.3 m x 4.3 m, 1.0 m door), ``corner-room``
(3.8 m x 5.2 m, 1.0 m door).

Prints one table: per explorer and room, and pooled over the rooms, the mean escape time with its 95 % Student-t
confidence interval, the median and the longest, and how many runs never escaped within the cap. A run that never
escaped counts as the cap, so with any such run the mean is a lower bound (shown with ``>=``). With the defaults it
takes about 6 minutes on one core, most of it the paper's explorer running to the cap.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import numpy as np
from scipy import stats

import amronet
from amronet.sim import Simulation


@dataclass(frozen=True)
class Room:
    """A room with one door: its interior (metres) and the base station inside it."""

    name: str
    map: str
    interior: tuple[float, float, float, float]
    """``(xmin, xmax, ymin, ymax)`` of the free space inside the walls."""
    base: tuple[float, float]
    door: str


ROOMS = {r.name: r for r in (
    Room("small-office", "office-32x32", (2.15, 4.95, 8.55, 14.85), (3.55, 11.7), "1.0 m, top"),
    Room("office", "office-32x32", (6.05, 10.45, 2.15, 8.45), (8.25, 5.3), "1.2 m, bottom"),
    Room("wide-room", "office-32x32", (2.15, 8.45, 17.15, 21.45), (5.3, 19.3), "1.0 m, left"),
    Room("corner-room", "office-32x32", (17.15, 20.95, 17.15, 22.35), (19.05, 19.75), "1.0 m, top"),
)}
"""Built-in rooms with one door (``office-32x32``, see ``tools/make_builtin_maps.py``)."""

CLEAR_M = 0.4
"""An agent is out when its centre is this far outside the room's interior: past the wall (0.15 m at most on
``office-32x32``) and its radius (0.22 m for the Pioneer), so its body has cleared the doorway."""


def escape_time(room: Room, explorer: str, seed: int, cap: float, *, r_c: float = 3.0, agents: int = 1,
                params: dict[str, float] | None = None) -> float:
    """Simulated seconds until the first agent is out of ``room`` (:data:`CLEAR_M`); ``inf`` if none is by ``cap``.

    Args:
        room: The room and its base station.
        explorer: ``algorithm.params.explorer``.
        seed: The run's seed.
        cap: Simulated seconds at most.
        r_c: Communication radius, metres.
        agents: Agents at the base station.
        params: Further ``algorithm.params`` (e.g. ``{"avoid_range": 0.4}``).
    """
    overrides: dict[str, object] = {
        "map": room.map, "radio.r_c": r_c, "agents.per_base": agents, "sim.time_limit": cap,
        "algorithm.params.explorer": explorer,
        "base_stations": [{"x": room.base[0], "y": room.base[1], "region": [1.6, 1.6]}],
    }
    for key, value in (params or {}).items():
        overrides[f"algorithm.params.{key}"] = value
    sim = Simulation(amronet.load_scenario("agent-assisted-office", overrides=overrides), seed)
    x0, x1, y0, y1 = np.array(room.interior) + np.array([-CLEAR_M, CLEAR_M, -CLEAR_M, CLEAR_M])
    for _ in range(round(cap / sim.dt)):
        sim.step()
        xy = sim.swarm.xy[sim.agents]
        if ((xy[:, 0] < x0) | (xy[:, 0] > x1) | (xy[:, 1] < y0) | (xy[:, 1] > y1)).any():
            return sim.t
    return math.inf


def summarize(times: list[float], cap: float) -> dict[str, object]:
    """Mean (never escaped counted as ``cap``), 95 % Student-t half-width, median, max and never-escaped count."""
    t = np.minimum(np.array(times, dtype=float), cap)
    never = int(np.count_nonzero(~np.isfinite(times)))
    half = float(stats.t.ppf(0.975, len(t) - 1) * t.std(ddof=1) / math.sqrt(len(t))) if len(t) > 1 else math.nan
    return {"mean": float(t.mean()), "ci": half, "median": float(np.median(t)), "max": float(t.max()),
            "never": never, "n": len(t)}


def _row(explorer: str, room: str, s: dict[str, object], cap: float) -> str:
    bound = ">=" if s["never"] else ""
    top = f">={cap:g}" if s["never"] else f"{s['max']:.1f}"
    return (f"| {explorer} | {room} | {bound}{s['mean']:.1f} | ± {s['ci']:.1f} | {s['median']:.1f} | {top} "
            f"| {s['never']} / {s['n']} |")


def main(argv: list[str] | None = None) -> None:
    """Measure and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=50, help="runs per explorer and room (seeds 1..N)")
    ap.add_argument("--cap", type=float, default=1200.0, help="simulated seconds per run at most")
    ap.add_argument("--explorers", nargs="+", default=["random", "random-escape"])
    ap.add_argument("--rooms", nargs="+", default=list(ROOMS), choices=list(ROOMS))
    ap.add_argument("--r-c", type=float, default=3.0, help="communication radius, metres")
    ap.add_argument("--agents", type=int, default=1, help="agents at the base station (the first out counts)")
    ap.add_argument("--avoid-range", type=float, default=None, help="algorithm.params.avoid_range (default 0.6)")
    args = ap.parse_args(argv)
    params = {} if args.avoid_range is None else {"avoid_range": args.avoid_range}
    print(f"{args.seeds} seeds per cell, cap {args.cap:g} s, r_c {args.r_c:g} m, {args.agents} agent(s)"
          + (f", avoid_range {args.avoid_range:g} m" if params else ""), flush=True)
    print("| explorer | room | mean escape (s) | 95 % CI | median | max | never escaped |")
    print("|---|---|---:|---:|---:|---:|---:|", flush=True)
    started = time.perf_counter()
    for explorer in args.explorers:
        pooled: list[float] = []
        for name in args.rooms:
            times = [escape_time(ROOMS[name], explorer, seed, args.cap, r_c=args.r_c, agents=args.agents,
                                 params=params) for seed in range(1, args.seeds + 1)]
            pooled += times
            print(_row(explorer, f"{name} ({ROOMS[name].door} door)", summarize(times, args.cap), args.cap), flush=True)
        if len(args.rooms) > 1:
            print(_row(explorer, "**all rooms**", summarize(pooled, args.cap), args.cap), flush=True)
    print(f"\n{time.perf_counter() - started:.0f} s wall time")


if __name__ == "__main__":
    main()
