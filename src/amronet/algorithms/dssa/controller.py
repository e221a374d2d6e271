"""DSSA, the distributed self-spreading algorithm of Heo & Varshney (IEEE WCNC 2003), as a baseline (paper 3, 5.2).

Every router repels the nodes it hears, more strongly the more crowded it is compared with the expected
density, and the push fades to zero at the communication radius::

    f_ij = (D_i / mu^2) (r_c - d_ij) u_ij,        mu = N pi r_s^2 / A

with ``D_i`` the number of nodes router ``i`` hears (its local density), ``u_ij`` the unit vector from ``j`` to
``i``, ``N`` the number of nodes (routers and base nodes), ``A`` the area of the field and ``r_s`` the sensing
radius. The AMRoNet paper (5.2.1, 6.2) runs DSSA with a *virtual* sensing radius ``r_s = 0.5 r_c`` so that
maximizing sensing coverage with ``2 r_s`` is maximizing communication coverage; that is the default here. The
summed force is the router's displacement for the step, limited to what its maximum speed allows in one step.

Stop rules (Heo & Varshney's oscillation and stability rules):

* **oscillation** — a router whose step reverses its previous step's direction ``oscillation_limit`` times
  while it stays within ``oscillation_radius r_c`` of where the count started moves to the centre of the
  positions it took meanwhile and stops;
* **stability** — a router that moves less than ``stable_fraction`` of its maximum step for ``stable_steps``
  steps in a row stops.

A stopped router is in state *reference* and never moves again; the run has converged when every router has
stopped (:attr:`DSSA.settled`).

Obstacles (paper 5.2.1, experiment 2: "forces from the obstacles are also added"): with ``obstacle_forces``, every
beam of the router's range sensors that sees something within range acts as a virtual neighbour at that
distance, with the same law times ``obstacle_gain``. The paper does not give the form it used; this is our
choice, like the defaults of ``oscillation_limit``, ``oscillation_radius``, ``stable_fraction``,
``stable_steps`` and ``obstacle_gain``, which Heo & Varshney leave open.

``A`` defaults to the free area of the map (what a deployment in a known field assumes); set ``field_area`` to
override it.
"""

from __future__ import annotations

import math

import numpy as np

from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput
from amronet.algorithms.common.forces import clamp_norm, links_of, obstacle_hits, sum_per_node
from amronet.algorithms.dssa.params import DSSAParams
from amronet.engine.robots import Role, State
from amronet.engine.streams import RunStreams
from amronet.errors import ScenarioError

__all__ = ["DSSA", "DSSAParams"]


def _expected_density(nodes: int, r_s: float, area: float, r_c: float, field: str) -> float:
    """``mu = N pi r_s^2 / A``, checked so that the force law ``D / mu^2 (r_c - d)`` stays a finite number.

    Raises:
        ScenarioError: ``mu`` so large or so small that ``mu^2`` or the force overflows (a field area or a range
            far from any floor plan's), naming ``field``.
    """
    try:
        mu = nodes * np.pi * r_s**2 / area
        scale = max(nodes, 1) * r_c / mu**2
    except (OverflowError, ZeroDivisionError):
        scale = math.inf
    if not (math.isfinite(scale) and scale > 0):
        raise ScenarioError(field, f"DSSA's expected density mu = N pi r_s^2 / A (N = {nodes} nodes, r_s = {r_s:g} m, "
                                   f"A = {area:g} m²) is out of the range its force law can compute with; give a "
                                   "field area and a range of a real floor plan")
    return mu


@ALGORITHMS.register("dssa")
class DSSA(Controller):
    """Controller of DSSA routers."""

    Params = DSSAParams
    params: DSSAParams
    batchable = True

    def __init__(self, params: DSSAParams, setup: Setup) -> None:
        super().__init__(params, setup)
        sw, p = self.swarm, self.params
        n = len(sw)
        self.routers = np.flatnonzero(sw.role == Role.ROUTER)
        area = p.field_area if p.field_area is not None else self.area.free_area_m2
        # N of one run (the runs of a batch are runs of one scenario: each has as many nodes)
        one_run = slice(*setup.rng.starts[:2]) if isinstance(setup.rng, RunStreams) else slice(None)
        nodes = int(np.count_nonzero(sw.role[one_run] != Role.AGENT))
        r_s = p.sensing_radius_factor * self.r_c
        self.mu = _expected_density(nodes, r_s, area, self.r_c, "algorithm.params.field_area"
                                    if p.field_area is not None else "radio.r_c")
        self.last_step = np.zeros((n, 2))
        self.anchor = sw.xy.copy()
        self.reversals = np.zeros(n, dtype=np.int64)
        self.visit_sum = sw.xy.copy()
        self.visit_count = np.ones(n, dtype=np.int64)
        self.still_steps = np.zeros(n, dtype=np.int64)
        self.finishing = np.zeros(n, dtype=bool)
        self.goal = sw.xy.copy()
        self.before = sw.xy.copy()
        self.stops = np.zeros((2, n), dtype=np.int64)
        """Per robot, how often the oscillation rule (row 0) and the stability rule (row 1) stopped it."""

    @property
    def needs_range_readings(self) -> bool:  # noqa: D102
        return self.params.obstacle_forces and self.params.obstacle_gain > 0

    def unsettled(self) -> np.ndarray:  # noqa: D102
        return (self.swarm.state == State.EXPLORE) & (self.swarm.role == Role.ROUTER)

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw, p = self.swarm, self.params
        movers = self.routers[sw.state[self.routers] == State.EXPLORE]
        if len(movers) == 0:
            return Command(movers, np.zeros(0))
        n = len(sw)
        links = links_of(step.table, sw.xy, movers)
        density = np.diff(step.table.indptr)[links.row].astype(float)
        magnitude = density / self.mu**2 * (self.r_c - links.dist)
        force = sum_per_node(links.row, links.away * magnitude[:, None], n)
        if p.obstacle_forces and p.obstacle_gain > 0:
            model = int(sw.model[movers[0]])
            scans = step.readings.of(movers, model)
            hits = obstacle_hits(scans, sw.heading[movers], sw.models[model].sensor_range)
            own = movers[hits.row]
            push = p.obstacle_gain * np.diff(step.table.indptr)[own] / self.mu**2 * (self.r_c - hits.dist)
            force += sum_per_node(own, hits.away * push[:, None], n)
        move = force[movers]
        fin = self.finishing[movers]
        move[fin] = self.goal[movers[fin]] - sw.xy[movers[fin]]
        max_step = sw.max_speed[movers] * self.dt
        move = clamp_norm(move, max_step)
        length = np.hypot(move[:, 0], move[:, 1])
        sw.heading[movers] = np.where(length > 0, np.arctan2(move[:, 1], move[:, 0]), sw.heading[movers])
        reversed_ = np.einsum("ij,ij->i", move, self.last_step[movers]) < 0
        self.reversals[movers[reversed_ & ~fin]] += 1
        self.before[movers] = sw.xy[movers]
        return Command(movers, length / self.dt)

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        if len(movers) == 0:
            return
        sw, p = self.swarm, self.params
        xy = sw.xy[movers]
        moved = xy - self.before[movers]
        self.last_step[movers] = moved
        fin = self.finishing[movers]
        arrived = fin & ((np.hypot(*(self.goal[movers] - xy).T) <= 1e-9) | refused)
        # oscillation bookkeeping: restart the count when the router leaves its oscillation region
        left = np.hypot(*(xy - self.anchor[movers]).T) > p.oscillation_radius * self.r_c
        restart = movers[left & ~fin]
        self.anchor[restart] = sw.xy[restart]
        self.reversals[restart] = 0
        self.visit_sum[restart] = sw.xy[restart]
        self.visit_count[restart] = 1
        stay = movers[~left & ~fin]
        self.visit_sum[stay] += sw.xy[stay]
        self.visit_count[stay] += 1
        oscillating = movers[~fin & ~left & (self.reversals[movers] >= p.oscillation_limit)]
        self.finishing[oscillating] = True
        self.goal[oscillating] = self.visit_sum[oscillating] / self.visit_count[oscillating, None]
        self.stops[0, oscillating] += 1
        # stability: standing still for stable_steps steps in a row
        still = np.hypot(moved[:, 0], moved[:, 1]) < p.stable_fraction * sw.max_speed[movers] * self.dt
        self.still_steps[movers] = np.where(still, self.still_steps[movers] + 1, 0)
        stable = ~fin & (self.still_steps[movers] >= p.stable_steps)
        self.stops[1, movers[stable]] += 1
        sw.state[movers[arrived | stable]] = State.REFERENCE

    @property
    def stopped_by(self) -> dict[str, int]:
        """How many routers each rule stopped (of every run of a batch)."""
        oscillation, stability = self.stops.sum(axis=1).tolist()
        return {"oscillation": oscillation, "stability": stability}

    def report(self) -> dict[str, object]:
        """How the routers stopped: by the oscillation rule or the stability rule."""
        return self.report_run(slice(None))

    def report_run(self, robots: slice) -> dict[str, object]:  # noqa: D102
        oscillation, stability = self.stops[:, robots].sum(axis=1).tolist()
        return {"stopped_by_oscillation": oscillation, "stopped_by_stability": stability,
                "expected_density_mu": self.mu}
