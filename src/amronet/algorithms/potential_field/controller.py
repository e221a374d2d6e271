"""Potential-field spreading: Poduri & Sukhatme's constrained coverage (ICRA 2004) and Howard et al.'s plain field.

The baseline the AMRoNet paper calls "potential field" (3, 5.2.1) is constrained coverage with K-connectivity.
For the links a router hears (only within ``r_c``), with ``u_ij`` the unit vector from ``j`` to ``i``::

    F_cover(i, j)  =  K_cover / d_ij^2 u_ij                   (repulsive, every link)
    F_degree(i, j) = -K_degree / (d_ij - Q r_c)^2 u_ij        (attractive, critical links only)

A router's links are *critical* when it hears ``K`` or fewer nodes: losing one would drop its degree below
``K``. ``Q`` is the safety factor: the pull of a critical link grows without bound as it stretches toward
``Q r_c``, so it does not break. Motion has viscous friction, integrated semi-implicitly::

    a = (F - nu v) / m;   v += a dt;   |v| <= v_max;   x += v dt

With ``connectivity_k = 0`` no link is ever critical and what remains is Howard, Matarić & Sukhatme's potential
field (DARS 2002): every node and obstacle point pushes with ``k / r^2``.

Published values (paper 5.2.1, from Poduri & Sukhatme): damping ``nu = 0.25`` and safety factor ``Q = 0.8``; ``K``
= 1 is the 1-connectivity an AMRoNet needs. Our choices (the published derivation of ``K_cover`` and ``K_degree``
was not at hand; see ``docs/baselines.md``):

* ``K_cover = nu v_max r_s^2`` — two nodes at the virtual sensing radius ``r_s = 0.5 r_c`` (paper 6.2) repel
  each other just hard enough to drive at the robot's maximum speed against the friction;
* ``K_degree`` balances ``K_cover`` at the link length ``d* = balance_fraction Q r_c`` (default 0.75, i.e.
  0.6 r_c): ``K_cover / d*^2 = K_degree / (Q r_c - d*)^2``;
* mass ``m`` = 1; a single link's or obstacle point's force magnitude is capped at ``force_cap_factor nu v_max``
  (default 4: four times the force that holds full speed against the friction) so that the singularities at
  ``d -> 0`` and ``d -> Q r_c`` stay finite and the motion does not chatter; a critical link longer than
  ``Q r_c`` pulls with the cap;
* obstacles: each beam of the range sensors that sees something at distance ``d`` pushes with
  ``K_obstacle / d^2`` (``K_obstacle = K_cover`` by default), when ``obstacle_forces`` is on (paper's
  experiment 2).

Convergence ("coming to rest"): a router rests (state *reference*) when, over a window of ``rest_steps`` steps,
it got no farther from where the window started than a router creeping at ``rest_fraction v_max`` would (jitter
in place counts as rest, drifting does not), and either the force on it would drive it at no more than twice
that speed, or its last move was refused: a wall (or another body) holds it and takes up the force. It rests
under the force it feels at that moment, the *held* force (about zero, or the push a wall takes up), and wakes
up (state *explore*) when the force on it differs from the held force by more than that threshold: when its
neighbourhood changed. The run has converged when every router rests (:attr:`PotentialField.settled`).
Without the held force a router pinned against the outer wall could never rest.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput
from amronet.algorithms.common.forces import inverse_square_obstacle_forces
from amronet.algorithms.common.swarm_data import robots_of
from amronet.algorithms.potential_field.kernel_data import field_constants_of, field_state_of
from amronet.algorithms.potential_field.kernels import come_to_rest, wake_and_accelerate
from amronet.algorithms.potential_field.params import PotentialFieldParams
from amronet.algorithms.stepping import FastStep, StepContext
from amronet.engine.kernel_data import Csr
from amronet.engine.robots import Role, State, state_lookup

__all__ = ["PotentialField", "PotentialFieldParams"]


@ALGORITHMS.register("potential-field")
class PotentialField(Controller):
    """Controller of potential-field routers."""

    Params = PotentialFieldParams
    params: PotentialFieldParams
    batchable = True

    def __init__(self, params: PotentialFieldParams, setup: Setup) -> None:
        super().__init__(params, setup)
        sw, p = self.swarm, self.params
        n = len(sw)
        self.routers = np.flatnonzero(sw.role == Role.ROUTER)
        v_max = float(sw.max_speed[self.routers].max(initial=0.0))
        r_s = p.sensing_radius_factor * self.r_c
        self.k_cover = p.k_cover if p.k_cover is not None else p.damping * v_max * r_s**2
        q_rc = p.safety_factor * self.r_c
        d_star = p.balance_fraction * q_rc
        self.k_degree = p.k_degree if p.k_degree is not None else self.k_cover * (q_rc - d_star) ** 2 / d_star**2
        self.k_obstacle = p.k_obstacle if p.k_obstacle is not None else self.k_cover
        self.q_rc = q_rc
        self.force_cap = p.force_cap_factor * p.damping * v_max if v_max > 0 else np.inf
        self.velocity = np.zeros((n, 2))
        self.obstacle_force = np.zeros((n, 2))
        self.rest_count = np.zeros(n, dtype=np.int64)
        self.window_start = sw.xy.copy()
        self.force = np.zeros((n, 2))
        self.held_force = np.zeros((n, 2))
        self.wakeups = np.zeros(n, dtype=np.int64)
        """How often every router woke up from rest."""

    @property
    def needs_range_readings(self) -> bool:  # noqa: D102
        return self.params.obstacle_forces

    def unsettled(self) -> np.ndarray:  # noqa: D102
        return (self.swarm.state == State.EXPLORE) & (self.swarm.role == Role.ROUTER)

    def settling_rule(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`unsettled` for compiled callers: ``(lookup, robots)``, unsettled where ``lookup[state] & robots``."""
        return state_lookup((State.EXPLORE,)), self.swarm.role == Role.ROUTER

    def fast_step(self, context: StepContext) -> FastStep | None:
        """The compiled sense, decide and move (:class:`.fast.CompiledField`) where it applies."""
        from amronet.algorithms.potential_field.fast import CompiledField  # (its kernels load with it)

        return CompiledField(self, context) if CompiledField.applies(self, context) else None

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw, p = self.swarm, self.params
        state = sw.state[self.routers]
        sensed = self.routers[state == State.EXPLORE]  # sensed this step; woken routers use their last reading
        if p.obstacle_forces and len(sensed):
            model = int(sw.model[sensed[0]])
            scans = step.readings.of(sensed, model)
            self.obstacle_force[sensed] = inverse_square_obstacle_forces(
                scans, sw.heading[sensed], sw.models[model].sensor_range, self.k_obstacle, self.force_cap)
        table = step.table
        movers = np.empty(len(self.routers), dtype=np.int64)
        speed = np.empty(len(self.routers))
        n_movers = wake_and_accelerate(
            self.routers, robots_of(sw), Csr(table.indptr, table.indices, table.dist), field_state_of(self),
            field_constants_of(self, self.dt), np.int64(State.EXPLORE), np.int64(State.REFERENCE), movers,
            speed)
        return Command(movers[:n_movers], speed[:n_movers])

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        if len(movers) == 0:
            return
        come_to_rest(np.asarray(movers, dtype=np.int64), np.asarray(refused, dtype=np.bool_), robots_of(self.swarm),
                     field_state_of(self), field_constants_of(self, self.dt), np.int64(State.REFERENCE))

    def report(self) -> dict[str, object]:
        """The force constants used and how often resting routers woke up."""
        return self.report_run(slice(None))

    def report_run(self, robots: slice) -> dict[str, object]:  # noqa: D102
        return {"k_cover": self.k_cover, "k_degree": self.k_degree, "k_obstacle": self.k_obstacle,
                "wakeups": int(self.wakeups[robots].sum())}


# -- compiled kernels: one pass over the routers per phase (30 robots are all overhead in NumPy) -----------------
