"""Self-spreading (paper section 4.2, with the triangular deployment and optimizations of 4.3).

Routers start at the base stations with status -1 in state *explore* and random-walk with obstacle avoidance.
Each keeps a current reference (a base node or deployed router within ``r_c``). A router that is **about to
lose its last reference** — every reference it hears is at least ``(1 - loss_margin) r_c`` away — stops,
becomes a *reference* and takes the status of its current reference. A router whose current reference has
status ``i`` that hears a reference of status ``p != i`` goes into *triangle* state with status ``i`` and drives
to the triangular goal point (:mod:`amronet.algorithms.triangular`); it settles there, or earlier when it is
blocked for ``give_up_steps`` steps in a row, or when a move would take it farther than
``(1 - loss_margin) r_c`` from either of its two references.

Everything a router decides comes from its own range readings and its own row of the neighbour table:
distances to the nodes within ``r_c`` and what they announce (state, status, the local-rule flag, position for
the triangle goal). The ``global`` rule additionally asks the deployed network whether two components are
already joined, which is the paper's global-communication strategy.

Why ``loss_margin`` default 0.05: a router moves at most ``max_speed * dt`` per step and must not cross the band
``[(1 - loss_margin) r_c, r_c]`` in one step, or it would lose its reference before noticing. With the Bebot
defaults (0.2 m/s, dt 0.1 s) one step is 0.02 m, well inside the 0.05 m band at ``r_c`` = 1 m. The band is
checked against the step length when a run starts.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictInt

from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput
from amronet.algorithms.goto import GoalSteering
from amronet.algorithms.references import check_loss_band, track_references
from amronet.algorithms.triangular import TriangularMode, select_triangles, triangle_goal
from amronet.engine.motion import random_walk
from amronet.engine.robots import SETTLING_STATES, Role, State

__all__ = ["SelfSpreading", "SelfSpreadingParams"]


class SelfSpreadingParams(BaseModel):
    """Parameters of self-spreading.

    Attributes:
        triangular: Triangular deployment: ``off`` (greedy only, an ablation), ``none`` (triangular deployment
            without optimization), ``global`` or ``local`` (the optimizations of paper 4.3).
        loss_margin: Width of the "about to lose" band as a fraction of ``r_c``.
        turn_noise: Heading noise of the random walk, radians per square-root second.
        give_up_steps: Consecutive blocked steps after which a triangle router stops short of its goal.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    triangular: TriangularMode = "local"
    loss_margin: Annotated[float, Field(strict=True, gt=0, lt=0.5, allow_inf_nan=False)] = 0.05
    turn_noise: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 1.0
    give_up_steps: Annotated[StrictInt, Field(ge=1)] = 20


@ALGORITHMS.register("self-spreading")
class SelfSpreading(Controller):
    """Controller of self-spreading routers."""

    Params = SelfSpreadingParams
    params: SelfSpreadingParams
    batchable = True

    def __init__(self, params: SelfSpreadingParams, setup: Setup) -> None:
        super().__init__(params, setup)
        sw = self.swarm
        n = len(sw)
        routers = sw.role == Role.ROUTER
        step = float(sw.max_speed[routers].max(initial=0.0)) * self.dt
        self.r_eff = check_loss_band(self.params.loss_margin, self.r_c, step, "router")
        self.current = np.full(n, -1, dtype=np.int64)
        self.steering = GoalSteering(n, n_anchors=2, give_up_steps=self.params.give_up_steps)
        self.disabled = np.zeros(n, dtype=bool)
        self.refused = np.zeros(n, dtype=bool)
        self.router_model = int(sw.model[routers][0]) if routers.any() else 0
        self.several_statuses = len(np.unique(sw.status[sw.role == Role.BASE])) > 1

    @classmethod
    def start_range(cls, params: SelfSpreadingParams, r_c: float) -> float:  # noqa: D102
        return (1.0 - params.loss_margin) * r_c

    def unsettled(self) -> np.ndarray:  # noqa: D102
        return self.swarm.in_states(SETTLING_STATES)

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw = self.swarm
        explorers = np.flatnonzero(sw.state == State.EXPLORE)
        if len(explorers):
            self._decide_explorers(step, explorers)
        movers = np.flatnonzero(sw.in_states(SETTLING_STATES))
        speed = sw.max_speed[movers].copy()
        if len(movers) == 0:
            return Command(movers, speed)
        model = self.router_model
        scans = step.readings.of(movers, model)
        sensor_range = sw.models[model].sensor_range
        walking = sw.state[movers] == State.EXPLORE
        w = movers[walking]
        sigma = self.params.turn_noise * np.sqrt(self.dt)
        everyone = len(w) == len(movers)
        random_walk(sw.heading, w, scans if everyone else scans[walking], sensor_range, self.refused[w], self.rng,
                    sigma)
        tri = movers[~walking]
        if len(tri):
            speed[~walking] = self._steer_triangles(tri, scans[~walking], sensor_range)
        return Command(movers, speed)

    def _decide_explorers(self, step: StepInput, explorers: np.ndarray) -> None:
        sw = self.swarm
        is_ref = sw.deployed
        view = track_references(step.table, explorers, self.current[explorers], is_ref, sw.status,
                                want_other=self.several_statuses and self.params.triangular != "off")
        self.current[explorers] = view.current

        triangles = np.zeros(len(explorers), dtype=bool)
        if self.params.triangular != "off":
            cand = np.flatnonzero(view.other >= 0)
            if len(cand):
                committed = is_ref | (sw.state == State.TRIANGLE)
                go = select_triangles(
                    self.params.triangular, explorers[cand], view.current[cand], view.other[cand], sw.xy,
                    self.r_c, self.disabled, step.table, committed,
                )
                triangles[cand[go]] = True
        if triangles.any():
            who = explorers[triangles]
            ref_i, ref_j = view.current[triangles], view.other[triangles]
            sw.state[who] = State.TRIANGLE
            sw.status[who] = sw.status[ref_i]
            goal = triangle_goal(sw.xy[ref_i], sw.xy[ref_j], sw.xy[who], self.r_eff)
            self.steering.start(who, goal, np.stack([ref_i, ref_j], axis=1))
            if self.params.triangular == "local":
                self.disabled[np.concatenate([who, ref_i, ref_j])] = True

        losing = view.has_reference & (view.nearest_distance >= self.r_eff) & ~triangles
        who = explorers[losing]
        sw.state[who] = State.REFERENCE
        sw.status[who] = sw.status[view.current[losing]]

    def _steer_triangles(self, tri: np.ndarray, scans: np.ndarray, sensor_range: float) -> np.ndarray:
        sw = self.swarm
        length, done = self.steering.steer(tri, sw.xy, sw.heading, scans, sensor_range,
                                           sw.max_speed[tri] * self.dt, self.r_eff)
        sw.state[tri[done]] = State.TRIANGLE_SETTLED
        return length / self.dt

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        self.refused[:] = False
        self.refused[movers] = refused
        tri = movers[self.swarm.state[movers] == State.TRIANGLE]
        arrived = np.linalg.norm(self.swarm.xy[tri] - self.steering.goal[tri], axis=1) <= 1e-9
        self.swarm.state[tri[arrived]] = State.TRIANGLE_SETTLED
