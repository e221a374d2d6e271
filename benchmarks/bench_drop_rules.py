"""CPU time per step of agent-assisted runs under each drop rule, switch, faults and repair, against the paper's rule.

Run: ``.venv/bin/python benchmarks/bench_drop_rules.py [--map hospital_section] [--radio unit-disk|multi-wall]
[--rounds 3] [--reference]``. One scenario, ``amronet reproduce buildings``'s (3 agents from one base station, the
frontier explorer, the map's ``r_c``), run for ``--seconds`` simulated seconds with the same seed under each case;
the CPU time of the run over its steps, and the time of sense, decide and move alone (the loop's phase timer: the
step's own cost, without the radio and the metrics, whose cost grows with the relays a rule drops), the median of
``--rounds`` rounds, every case once per round in turn. The ratios are to the paper's rule (``last-reference``) on the
same scenario (target: within 1.5); ``relays``: the routers the agents put down in the run (the same in every round:
the same seed). The faults cases fail 30 % of the routers at half time (``coverage_target``
off); the repair cases repair them as ``reproduce failures`` does. ``--reference`` adds the
phase-by-phase path's cost of each case (what a run without the compiled step costs).
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

import numpy as np

from amronet.engine.robots import Role
from amronet.experiments.buildings import BUILDINGS, RADIOS
from amronet.experiments.common import agent_scenario
from amronet.experiments.failures import WALL_DROP_RULE
from amronet.scenario import load_scenario
from amronet.sim import Simulation

CASES: dict[str, tuple[str, dict[str, Any], dict[str, Any]]] = {
    "last-reference (the paper's)": ("last-reference", {}, {}),
    "link-quality": ("link-quality", {}, {}),
    "radius": ("radius", {}, {}),
    "distance-junction": ("distance-junction", {}, {}),
    "strip-goals": ("strip-goals", {}, {}),
    "when_empty continue, stock 6": ("last-reference", {"routers_carried": 6, "when_empty": "continue"}, {}),
    "drop_settle_s 2": ("last-reference", {"drop_settle_s": 2.0}, {}),
    "reverse_drop 5 s (distance-junction)": ("distance-junction", {"reverse_drop": 5.0}, {}),
    "faults: 30 % of routers at half time": ("last-reference", {}, {"faults": "half"}),
    "faults + repair: relocate": ("failures", {}, {"faults": "half", "repair": "relocate"}),
    "faults + repair: retrace": ("failures", {}, {"faults": "half", "repair": "retrace"}),
}
"""Label → (drop rule, ``agents`` fields, extras). Drop rule ``failures``: ``reproduce failures``' for the radio (the
paper's on the unit disk, :data:`~amronet.experiments.failures.WALL_DROP_RULE` behind walls, where the paper's rule
drops no relay to fail)."""


def _scenario(map_name: str, radio: str, seconds: float, case: str) -> dict[str, Any]:
    rule, agents, extra = CASES[case]
    if rule == "failures":
        rule = "last-reference" if radio == "unit-disk" else WALL_DROP_RULE
    b = BUILDINGS[map_name]
    sc = agent_scenario(b.map, b.r_c, (b.base,), 3, "frontier", seconds, radio=RADIOS[radio], drop_rule=rule,
                        agents=agents)
    if extra.get("faults"):
        sc["faults"] = [{"at": seconds / 2, "routers": 0.3}]
        sc["sim"] = {**sc["sim"], "coverage_target": "off"}
    if extra.get("repair"):  # as ``reproduce failures`` sets its repair rules
        sc["algorithm"]["params"]["repair"] = extra["repair"]
    return sc


def _per_step(sc: dict[str, Any], seed: int, step: str) -> tuple[float, float, int]:
    """CPU seconds per step of the whole run, wall seconds per step of sense, decide and move alone, relays put down."""
    sim = Simulation(load_scenario(sc), seed, step=step)
    t = time.process_time()
    sim.run()
    cpu = time.process_time() - t
    steps = max(sim.steps, 1)
    own = sum(v for k, v in sim.phase_seconds.items() if k != "radio")
    return cpu / steps, own / steps, int(np.count_nonzero(sim.swarm.role == Role.ROUTER))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--map", default="hospital_section", choices=sorted(BUILDINGS))
    parser.add_argument("--radio", default="unit-disk", choices=sorted(RADIOS))
    parser.add_argument("--seconds", type=float, default=300.0, help="simulated seconds per run")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--seed", type=int, default=70_001)
    parser.add_argument("--reference", action="store_true", help="also the phase-by-phase path")
    args = parser.parse_args()
    scenarios = {case: _scenario(args.map, args.radio, args.seconds, case) for case in CASES}
    steps = ("compiled", "reference") if args.reference else ("compiled",)
    for sc in scenarios.values():  # compile and load every kernel first
        for step in steps:
            _per_step(sc, args.seed, step)
    times: dict[tuple[str, str], list[tuple[float, float, int]]] = {
        (case, step): [] for case in CASES for step in steps}
    for _ in range(args.rounds):
        for case, sc in scenarios.items():
            for step in steps:
                times[case, step].append(_per_step(sc, args.seed, step))
    def median(case: str, step: str, k: int) -> float:
        return statistics.median(v[k] for v in times[case, step])

    paper, paper_own = median(next(iter(CASES)), "compiled", 0), median(next(iter(CASES)), "compiled", 1)
    print(f"{args.map}, {args.radio}, {args.seconds:g} s, seed {args.seed}; µs per step, median of {args.rounds}: the "
          "whole run's CPU time, and sense + decide + move alone (the loop's phase timer: no radio, no metrics)")
    extra = " reference (µs/step) |" if args.reference else ""
    print("| case | compiled (µs/step) | rounds | × paper's rule | sense+decide+move (µs/step) | × paper's rule "
          "| relays |" + extra)
    print("|---|---:|---|---:|---:|---:|---:|" + ("---:|" if args.reference else ""))
    for case in CASES:
        med, own = median(case, "compiled", 0), median(case, "compiled", 1)
        rounds = " / ".join(f"{1e6 * v[0]:.0f}" for v in times[case, "compiled"])
        line = (f"| {case} | {1e6 * med:.0f} | {rounds} | {med / paper:.2f} | {1e6 * own:.0f} | "
                f"{own / paper_own:.2f} | {times[case, 'compiled'][-1][2]} |")
        if args.reference:
            line += f" {1e6 * median(case, 'reference', 0):.0f} |"
        print(line, flush=True)


if __name__ == "__main__":
    main()
