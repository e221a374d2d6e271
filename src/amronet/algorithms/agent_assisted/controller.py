"""Agent-assisted router deployment (paper section 4.1, with the triangular deployment and optimizations of 4.3).

Agents explore from their base stations (a pluggable explorer; the paper's is random exploration with sonar
obstacle avoidance), or follow the paths a scenario gives them (``agents.trajectories``:
:mod:`amronet.algorithms.agent_assisted.explorers.trajectory`). Each agent keeps a current reference — a base node or
deployed
router within ``r_c`` — and takes its status. **Greedy deployment**: when every reference the agent hears is at least
``(1 - loss_margin) r_c`` away (it is about to lose the last one), it releases a router right next to itself,
on the side of its current reference (so the router is linked to it); the router takes the agent's status and
becomes a reference for every agent in its range. **Triangular deployment**: an agent whose current reference
has status ``i`` that hears a router of status ``p != i`` releases a router that drives to the triangle goal
point (:mod:`amronet.algorithms.common.triangular`, :mod:`amronet.algorithms.common.goto`) under the chosen rule.

Choices the paper leaves open, and ours:

* Where exactly the router is released: at ``agent radius + router radius + release_gap`` from the agent's
  centre toward the current reference; if that spot is blocked or taken, the nearest free direction (in steps
  of 30 degrees) that keeps the router within ``r_c`` of the reference and is reachable in a straight line;
  failing all, the same on two rings farther out (in steps of 15 degrees, the straight line clear of walls and
  bodies). A router is never put down on another body or a wall: with no free spot the agent releases nothing
  this step (about to lose its last reference, it turns back toward it, as a tethered agent does, and tries
  again; a triangle router is tried again at the next step).
* Triangular deployment is an event, not a state: the paper's agent releases a triangle router when it
  *encounters* a reference ``R_pq`` of another status from its current reference ``R_ij``. Each agent remembers
  the pairs ``{R_ij, R_pq}`` it has served and releases at most one triangle router per pair, in every mode
  (with ``none`` this is the only bound: at most ``agents x pairs`` triangle routers, where a pair is two
  references of different status more than ``r_c`` and at most ``2 r_c`` apart). Without it an agent that
  stays in range of both would release one at every step.
* An agent that has no router left (``agents.routers_carried``) is tethered: when it is about to lose its last
  reference it turns back toward its current reference instead of going on, so it never loses its connection.
* When the two references of a triangle are within ``r_c`` of each other no router is sent: they are linked.
* The run stops when the reachable free space is covered (``sim.coverage_target``; 0.99 when not set).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictInt, model_validator

from amronet.algorithms.agent_assisted.drops import DROP_RULES, AgentView, DropContext, validate_drop_params
from amronet.algorithms.agent_assisted.drops.trail import Trails
from amronet.algorithms.agent_assisted.explorers import EXPLORERS, Explorer, PathFollower
from amronet.algorithms.agent_assisted.kernels import track_agents
from amronet.algorithms.agent_assisted.relocate import Relocator
from amronet.algorithms.agent_assisted.strip_driving import StripDrivers
from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput, WarmUp
from amronet.algorithms.common.goto import GoalSteering
from amronet.algorithms.common.references import best_reference_margin, check_loss_band
from amronet.algorithms.common.triangular import TriangularMode, select_triangles, triangle_goal
from amronet.algorithms.stepping import FastStep, StepContext
from amronet.engine.network import agents_connected
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError

__all__ = ["AgentAssisted", "AgentAssistedParams"]

DEFAULT_COVERAGE_TARGET = 0.99


class AgentAssistedParams(BaseModel):
    """Parameters of agent-assisted router deployment.

    Attributes:
        triangular: ``off``, ``none``, ``global`` or ``local`` (see :mod:`amronet.algorithms.common.triangular`).
        loss_margin: Width of the "about to lose" band as a fraction of ``r_c``.
        explorer: Exploration strategy of the agents (:data:`amronet.algorithms.agent_assisted.explorers.EXPLORERS`).
        turn_noise: Heading noise of the agents' random exploration, radians per square-root second.
        avoid_range: Sonar readings nearer than this (metres) make an agent turn away.
        give_up_steps: Consecutive blocked steps after which a triangle router stops short of its goal.
        release_gap: Gap in metres between an agent's body and the router it releases.
        drop_rule: When an agent puts a router down (:data:`amronet.algorithms.agent_assisted.drops.DROP_RULES`); the
        paper's
            ``last-reference`` by default.
        drop: The drop rule's own parameters (e.g. ``{drop_margin_db: 3}`` for ``link-quality``).
        repair: ``none``, or ``relocate``: deployed routers that a failure cut off move to bridge the cut
            (:mod:`amronet.algorithms.agent_assisted.relocate`).
        repair_confirm_s: How long a neighbour must be missing before a router counts it as lost, seconds.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    triangular: TriangularMode = "local"
    loss_margin: Annotated[float, Field(strict=True, gt=0, lt=0.5, allow_inf_nan=False)] = 0.05
    explorer: str = "random"
    turn_noise: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 0.5
    avoid_range: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] = 0.6
    give_up_steps: Annotated[StrictInt, Field(ge=1)] = 20
    release_gap: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 0.02
    drop_rule: str = "last-reference"
    drop: dict[str, Any] = Field(default_factory=dict)
    repair: Literal["none", "relocate"] = "none"
    repair_confirm_s: Annotated[float, Field(strict=True, ge=0, le=600, allow_inf_nan=False)] = 1.0

    @model_validator(mode="after")
    def _check_drop_rule(self) -> AgentAssistedParams:
        rule = DROP_RULES.get(self.drop_rule)
        if rule is None:
            raise ValueError(f"@algorithm.params.drop_rule@unknown drop rule {self.drop_rule!r}; choose one of: "
                             + ", ".join(sorted(DROP_RULES)))
        validate_drop_params(rule, self.drop, "algorithm.params.drop")
        return self


def _pair_key(agent: int, ref_i: int, ref_j: int) -> tuple[int, int, int]:
    """The key of a triangle served by ``agent`` for the references ``ref_i`` and ``ref_j`` (either order)."""
    return (agent, min(ref_i, ref_j), max(ref_i, ref_j))


def _segments_clear(p: np.ndarray, ends: np.ndarray, r: float, xy: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Which segments ``p -> ends[m]`` a body of radius ``r`` can be carried along without touching a body."""
    seg = ends - p
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300)
    rel = xy - p
    t = np.clip((rel @ seg.T) / length2[None, :], 0.0, 1.0)
    closest = p[None, None, :] + t[:, :, None] * seg[None, :, :]
    d = np.linalg.norm(xy[:, None, :] - closest, axis=2)
    return (d >= r + radius[:, None]).all(axis=0)


@ALGORITHMS.register("agent-assisted")
class AgentAssisted(Controller):
    """Controller of agents that carry and release routers."""

    Params = AgentAssistedParams
    params: AgentAssistedParams
    default_coverage_target = DEFAULT_COVERAGE_TARGET
    follows_paths = True

    def __init__(self, params: AgentAssistedParams, setup: Setup) -> None:
        super().__init__(params, setup)
        sw, stock = self.swarm, setup.stock
        if stock is None:
            raise ScenarioError("agents.per_base", "agent-assisted deployment needs agents; set agents.per_base >= 1")
        agents = sw.role == Role.AGENT
        if not agents.any():
            raise ScenarioError("agents.per_base", "agent-assisted deployment needs agents; set agents.per_base >= 1")
        if (sw.role == Role.ROUTER).any():
            raise ScenarioError("routers.count", "agents release the routers in agent-assisted deployment; "
                                                 "set routers.count to 0")
        explorer_cls = EXPLORERS.lookup(self.params.explorer, "algorithm.params.explorer")
        step = float(sw.max_speed[agents].max()) * self.dt
        self.r_eff = check_loss_band(self.params.loss_margin, self.r_c, step, "agent")
        self.router_model = stock.robot
        self.path_clear = stock.path_clear
        carried = stock.per_agent
        n = len(sw)
        self.left = np.where(agents, np.inf if carried is None else float(carried), 0.0)
        self.current = np.full(n, -1, dtype=np.int64)
        self.disabled = np.zeros(n, dtype=bool)
        self.refused = np.zeros(n, dtype=bool)
        self.steering = GoalSteering(n, n_anchors=2, give_up_steps=self.params.give_up_steps)
        self.explorer = explorer_cls(self.params.turn_noise, self.params.avoid_range, self.dt,
                                                        self.r_c, self.area.extent)
        self.agents = np.flatnonzero(agents)
        self.agent_model = int(sw.model[self.agents[0]])
        self.several_statuses = len(np.unique(sw.status[sw.role == Role.BASE])) > 1
        self.released = 0
        self.agent_speed = sw.max_speed[self.agents]
        if setup.paths is not None:  # agents.trajectories: agents with a path follow it, the others explore
            self.explorer = PathFollower(setup.paths, self.explorer, self.dt, self.agent_speed, sw.radius[self.agents])
        self.moving_triangles = 0
        """Released triangle routers that have not reached their goal yet."""
        self.nearest_d = np.empty(len(self.agents))
        """Per agent, the distance to its nearest reference in range, as the last tracking found it."""
        self.other_ref = np.empty(len(self.agents), dtype=np.int64)
        """Per agent, its nearest reference of another status (-1: none), as the last tracking found it."""
        self._deployed: np.ndarray | None = None
        self._deployed_xy: np.ndarray | None = None
        self.triangles_released: list[tuple[int, int, int]] = []
        """Every triangle release as ``(agent, reference, reference)``, the references in increasing order."""
        self._served: set[tuple[int, int, int]] = set()
        # the drop rule and the realism switches (agents.when_empty, drop_settle_s, reverse_drop)
        rule_cls = DROP_RULES.lookup(self.params.drop_rule, "algorithm.params.drop_rule")
        sensor_range = sw.models[self.agent_model].sensor_range
        self.drop_rule = rule_cls(validate_drop_params(rule_cls, self.params.drop, "algorithm.params.drop"),
                                  DropContext(self.r_c, self.r_eff, self.dt, len(self.agents), sensor_range))
        self.tether = stock.when_empty == "tether"
        self.settle_s = stock.settle_s
        self.reverse_after_s = stock.reverse_after_s
        self.released_by = np.zeros(len(self.agents), dtype=np.int64)
        """Routers each agent has put down (references and triangle routers)."""
        self.bases = np.flatnonzero(sw.role == Role.BASE)
        self.pending_until = np.full(len(self.agents), -np.inf)
        """Until when each agent's last router is still settling (it drops no other meanwhile)."""
        self.settle_at: dict[int, float] = {}
        """Routers put down and not relaying yet → the time they start to."""
        self.contact_since = np.zeros(len(self.agents))
        """The last time each agent was in contact with a base station (reverse drop)."""
        self.reversing = np.zeros(len(self.agents), dtype=bool)
        self.reverse_drops = 0
        self.trails = (Trails(sw.xy[self.agents], spacing=0.125 * self.r_c) if self.reverse_after_s is not None
                       else None)
        self.general_path = (self.params.drop_rule != "last-reference" or self.settle_s > 0 or not self.tether
                             or self.reverse_after_s is not None)
        """Whether every step takes the general drop path (the paper's rule alone acts only on "about to lose")."""
        self.relocator = (Relocator(n, self.params.repair_confirm_s, self.params.give_up_steps)
                          if self.params.repair == "relocate" else None)
        self.strips = (StripDrivers(self.drop_rule, sw, self.steering, self.bases, self._nodes_changed)
                       if self.drop_rule.drives_to_goal else None)
        """strip-goals: the routers that drive on to a goal point after they are put down."""

    @classmethod
    def start_range(cls, params: AgentAssistedParams, r_c: float) -> float:  # noqa: D102
        return (1.0 - params.loss_margin) * r_c

    def unsettled(self) -> np.ndarray:
        """Agents that keep the run going, and routers on their way to a goal or settling.

        Exploring agents never settle (the coverage target ends the run); agents on a given path settle at its end.
        """
        out = self.swarm.in_states((State.TRIANGLE, State.RELOCATING, State.STRIP, State.DROPPED))
        out[self.agents] = self.explorer.active(len(self.agents))
        return out

    @property
    def settled(self) -> bool:  # noqa: D102
        if len(self.agents) and type(self.explorer).active is Explorer.active:
            return False  # agents that explore keep the run going: no need to look at every robot each step
        return not self.unsettled().any()

    # -- growing per-robot state when routers are released --------------------------------------------------
    def _grow(self, n_new: int) -> None:
        def pad(a: np.ndarray, fill: float | int | bool) -> np.ndarray:
            return np.concatenate([a, np.full((n_new, *a.shape[1:]), fill, dtype=a.dtype)])

        self.left = pad(self.left, 0.0)
        self.current = pad(self.current, -1)
        self.disabled = pad(self.disabled, False)
        self.refused = pad(self.refused, False)
        st = self.steering
        st.goal, st.anchors = pad(st.goal, 0.0), pad(st.anchors, -1)
        st.last_to_goal, st.blocked_steps = pad(st.last_to_goal, np.inf), pad(st.blocked_steps, 0)
        if self.relocator is not None:
            self.relocator.grow(n_new)

    # -- the deployed nodes (they change only when this controller releases a router or one settles) ---------
    def deployed_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        """Mask of the deployed nodes (base nodes and deployed routers) and their positions, cached.

        Deployed nodes never move, and only this controller changes robots' states (releasing a router, a
        triangle router settling), so the cache is dropped by :meth:`_nodes_changed` on those events.
        """
        if self._deployed is None:
            sw = self.swarm
            self._deployed = sw.deployed
            self._deployed_xy = sw.xy[self._deployed]
        assert self._deployed_xy is not None
        return self._deployed, self._deployed_xy

    def _nodes_changed(self) -> None:
        self._deployed = self._deployed_xy = None

    # -- the step -------------------------------------------------------------------------------------------
    def fast_step(self, context: StepContext) -> FastStep | None:
        """The compiled sense, decide and move (:class:`.fast.CompiledAgents`) where it applies."""
        from amronet.algorithms.agent_assisted.fast import CompiledAgents  # (its kernels load with it)
        from amronet.algorithms.agent_assisted.stretch import QuietStretch

        if not CompiledAgents.applies(self, context):
            return None
        fast = CompiledAgents(self, context)
        fast.quiet = QuietStretch(fast, context) if QuietStretch.applies(fast, context) else None
        return fast

    @classmethod
    def warm_ups(cls) -> list[WarmUp]:
        """The runs that compile its kernels ahead of a first run (:mod:`.warmups`)."""
        from amronet.algorithms.agent_assisted.warmups import warm_ups

        return warm_ups()

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw = self.swarm
        if self.settle_at:
            self._settle_dropped(step.t)
        n_before = len(sw)
        is_ref, _ = self.deployed_nodes()
        table = step.table
        n_cand, n_losing = track_agents(self.agents, self.current, is_ref, sw.status, table.indptr, table.indices,
                                        table.dist, self.wants_other, self.left, self.r_eff, self.nearest_d,
                                        self.other_ref)
        return self.decide_tracked(step, n_before, n_cand, n_losing)

    def served_pairs(self) -> np.ndarray:
        """The triangles served so far as rows ``(agent, lower reference, higher reference)`` ``(k, 3)`` int64."""
        return np.array(sorted(self._served), dtype=np.int64).reshape(-1, 3)

    @property
    def wants_other(self) -> bool:
        """Whether the reference tracking looks for a reference of another status (a triangle may start)."""
        return self.several_statuses and self.params.triangular != "off"

    def decide_tracked(self, step: StepInput, n_before: int, n_cand: int, n_losing: int) -> Command:
        """The rest of :meth:`decide` once the agents' references are tracked (:func:`track_agents`'s counts).

        ``n_before``: how many robots there were when the step began. A compiled step that tracks the agents in a
        pass of its own (:mod:`amronet.algorithms.agent_assisted.fast`) hands the steps in which an agent must act over
        here.
        """
        sw = self.swarm
        agents = self.agents
        is_ref, _ = self.deployed_nodes()
        table = step.table
        # the rare steps in which an agent must release a router (or turn back) take the general path below
        current = self.current[agents] if n_cand or n_losing else None

        if n_cand:
            assert current is not None
            other = self.other_ref
            cand = np.flatnonzero((other >= 0) & (self.left[agents] >= 1))
            if self._served:  # an agent serves a pair of references once
                fresh = [_pair_key(int(agents[m]), int(current[m]), int(other[m])) not in self._served for m in cand]
                cand = cand[np.array(fresh, dtype=bool)]
            committed = is_ref | (sw.state == State.TRIANGLE)
            go = select_triangles(self.params.triangular, agents[cand], current[cand], other[cand], sw.xy,
                                  self.r_c, self.disabled, table, committed)
            for m in cand[go]:
                self._release_triangle(int(agents[m]), int(current[m]), int(other[m]))

        losing = None
        held = None
        view = None
        if n_losing or self.general_path:
            if current is None:
                current = self.current[agents]
            view = self._view(step, current)
            losing = self.drop_rule.losing(view)
            drop = self.drop_rule.decide(view)
            if self.reversing.any():
                drop = self._reverse_drops(view, drop)
            dropped = np.zeros(len(agents), dtype=bool)
            for m in np.flatnonzero(drop):
                toward = self._toward(m, view)
                new = self._release_reference(int(agents[m]), toward, step.t) if toward >= 0 else None
                if new is not None:
                    dropped[m] = True
                    if losing[m] and sw.state[new] == State.STRIP:  # it drives off (strip-goals): wait for one to stay
                        if held is None:
                            held = np.zeros(len(agents), dtype=bool)
                        held[m] = True
                elif losing[m]:
                    if held is None:
                        held = np.zeros(len(agents), dtype=bool)
                    held[m] = True  # no free spot to put a router down: turn back as a tethered agent does
            if dropped.any():
                self.drop_rule.dropped(dropped, view)
                if self.settle_s > 0:
                    self.pending_until[dropped] = step.t + self.settle_s
                if self.reversing.any():
                    self.reverse_drops += int(np.count_nonzero(dropped & self.reversing))
                    self.reversing &= ~dropped

        # agents: explore, or turn back when tethered (no router left and about to lose the last reference)
        scans = step.readings.of(agents, self.agent_model)
        sensor_range = sw.models[self.agent_model].sensor_range
        self.explorer.steer(sw.heading, agents, scans, sensor_range, self.refused[agents], self.rng, sw.xy,
                            self.deployed_nodes()[1])
        if losing is not None:
            assert view is not None
            tethered = losing & (self.left[agents] < 1) if self.tether else np.zeros(len(agents), dtype=bool)
            if held is not None:
                tethered |= held
            for m in np.flatnonzero(tethered):
                toward = self._toward(m, view)
                if toward >= 0:
                    back = sw.xy[toward] - sw.xy[agents[m]]
                    sw.heading[agents[m]] = np.arctan2(back[1], back[0])
        if self.trails is not None:
            self._back_up(view)
        return self.movers_command(step, n_before)

    def movers_command(self, step: StepInput, n_before: int) -> Command:
        """The end of :meth:`decide` once the agents are steered: the other movers steer; the command for them all.

        The triangle, strip and relocating routers steer; the command moves them with the agents. A compiled step
        that steers the agents itself (:mod:`amronet.algorithms.agent_assisted.stretch`) finishes a step here.
        """
        sw = self.swarm
        agents = self.agents
        speed = self.explorer.speed(self.agent_speed)
        movers, speeds = [agents], [speed]

        # triangle routers released before this step drive to their goals
        if self.moving_triangles:
            tri = np.flatnonzero(sw.state[:n_before] == State.TRIANGLE)
            if len(tri):
                model = int(sw.model[tri[0]])
                tri_scans = step.readings.of(tri, model)
                length, done = self.steering.steer(tri, sw.xy, sw.heading, tri_scans, sw.models[model].sensor_range,
                                                   sw.max_speed[tri] * self.dt, self.r_eff)
                if done.any():
                    sw.state[tri[done]] = State.TRIANGLE_SETTLED
                    self.moving_triangles -= int(np.count_nonzero(done))
                    self._nodes_changed()
                movers.append(tri)
                speeds.append(length / self.dt)
        if self.strips is not None and self.strips.moving:
            moving, model = self._sensed_in(step, n_before, State.STRIP)
            if len(moving):
                length = self.strips.drive(moving, step.readings.of(moving, model), sw.models[model].sensor_range,
                                           sw.max_speed[moving] * self.dt)
                movers.append(moving)
                speeds.append(length / self.dt)
        if self.relocator is not None:
            moving, length = self._relocate(step, n_before)
            if len(moving):
                movers.append(moving)
                speeds.append(length / self.dt)
        if len(movers) == 1:
            return Command(agents, speed)
        return Command(np.concatenate(movers), np.concatenate(speeds))

    def _sensed_in(self, step: StepInput, n_before: int, state: int) -> tuple[np.ndarray, int]:
        """Routers in ``state`` sensed this step (those that entered it this step move from the next); their model."""
        sw = self.swarm
        moving = np.flatnonzero(sw.state[:n_before] == state)
        if not len(moving):
            return moving, 0
        model = int(sw.model[moving[0]])
        sensed = step.readings.groups.get(model, (np.zeros(0, dtype=np.int64), None))[0]
        return moving[np.isin(moving, sensed)], model

    def _relocate(self, step: StepInput, n_before: int) -> tuple[np.ndarray, np.ndarray]:
        """The relocation repair: start and stop relocations, steer the routers that relocate (sensed this step)."""
        assert self.relocator is not None
        sw = self.swarm
        started, stopped = self.relocator.update(step.t, step.table, sw)
        if len(started) or len(stopped):
            sw.state[started] = State.RELOCATING
            sw.state[stopped] = State.REFERENCE
            self._nodes_changed()
        moving, model = self._sensed_in(step, n_before, State.RELOCATING)
        if not len(moving):
            return moving, np.zeros(0)
        length, done = self.relocator.steering.steer(moving, sw.xy, sw.heading, step.readings.of(moving, model),
                                                     sw.models[model].sensor_range, sw.max_speed[moving] * self.dt,
                                                     self.r_eff)
        if done.any():  # arrived or blocked: it stays where it is and serves as a reference again
            sw.state[moving[done]] = State.REFERENCE
            self._nodes_changed()
        return moving, length

    # -- the drop rule's view and the realism switches ----------------------------------------------------------
    def _view(self, step: StepInput, current: np.ndarray) -> AgentView:
        """What the agents know this step (:class:`~amronet.algorithms.agent_assisted.drops.AgentView`)."""
        sw, agents, rule = self.swarm, self.agents, self.drop_rule
        is_ref, ref_xy = self.deployed_nodes()
        settling = sw.state == State.DROPPED
        relay_xy = np.concatenate([ref_xy, sw.xy[settling]]) if self.settle_at else ref_xy
        contact = None
        if rule.needs_contact or self.reverse_after_s is not None:
            contact = agents_connected(step.table, agents, self.bases, sw.relaying)
        best = (best_reference_margin(step.table, agents, is_ref) if not rule.reads_positions
                else np.full(len(agents), -np.inf))
        return AgentView(
            t=step.t, current=current, nearest_d=self.nearest_d, best_margin=best, xy=sw.xy[agents],
            heading=sw.heading[agents], relay_xy=relay_xy, base_xy=sw.xy[self.bases], in_contact=contact,
            scans=step.readings.of(agents, self.agent_model) if rule.needs_scans else None,
            can_drop=(self.left[agents] >= 1) & (self.pending_until <= step.t))

    def _toward(self, m: int, view: AgentView) -> int:
        """The node agent ``m`` puts a router down next to or turns back to (-1: none).

        Its current reference, or when it hears none, the nearest known relay.
        """
        if view.current[m] >= 0:
            return int(view.current[m])
        deployed = np.flatnonzero(self.deployed_nodes()[0])
        if len(deployed) == 0:
            return -1
        d = np.linalg.norm(self.swarm.xy[deployed] - view.xy[m], axis=1)
        return int(deployed[np.argmin(d)])

    def _settle_dropped(self, t: float) -> None:
        """Routers whose settling time is over start to relay and serve as references."""
        ready = [i for i, at in self.settle_at.items() if at <= t]
        if ready:
            self.swarm.state[ready] = State.REFERENCE
            for i in ready:
                del self.settle_at[i]
                if self.strips is not None:
                    self.strips.settled(i)
            self._nodes_changed()

    def _reverse_drops(self, view: AgentView, drop: np.ndarray) -> np.ndarray:
        """Agents backing up that are in contact again drop there (MARBLE's reverse drop)."""
        assert view.in_contact is not None
        return drop | (self.reversing & view.in_contact & view.can_drop)

    def _back_up(self, view: AgentView | None) -> None:
        """MARBLE's reverse drop: an agent out of contact for ``reverse_after_s`` backs up along its own path."""
        assert self.trails is not None and view is not None and view.in_contact is not None
        sw, agents = self.swarm, self.agents
        contact = view.in_contact
        self.contact_since[contact] = view.t
        self.reversing &= ~contact
        self.trails.update(sw.xy[agents], ~self.reversing)
        start = ~contact & ~self.reversing & (view.t - self.contact_since > self.reverse_after_s)
        self.reversing |= start & (self.left[agents] >= 1)
        for m in np.flatnonzero(self.reversing):
            target = self.trails.back(int(m), sw.xy[agents[m]])
            if target is None:  # back at the start of its path and still cut off: give up backing
                self.reversing[m] = False
                self.contact_since[m] = view.t
                continue
            d = target - sw.xy[agents[m]]
            sw.heading[agents[m]] = np.arctan2(d[1], d[0])

    def mission_report(self) -> dict[str, object]:
        """Relays used and who put them down, the drop rule and what it counted (the summary's ``mission``)."""
        out: dict[str, object] = {"drop_rule": self.params.drop_rule, "relays_used": int(self.released),
                                  "released_per_agent": [int(k) for k in self.released_by],
                                  "triangle_relays": len(self.triangles_released)}
        if self.reverse_after_s is not None:
            out["reverse_drops"] = self.reverse_drops
        if self.relocator is not None:
            out["relocations"] = self.relocator.moves
        if self.strips is not None:
            out["strip_goals"] = dict(self.strips.counts)
        out.update(self.drop_rule.report())
        out.update(self.explorer.report())
        return out

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        self.refused[:] = False
        self.refused[movers] = refused

    # -- releasing routers (cold: a handful of events per run) ---------------------------------------------
    def _release_spot(self, agent: int, toward: int) -> np.ndarray | None:
        """Where ``agent`` puts a router down, next to itself toward ``toward``; ``None`` when no spot is free.

        First the ring right next to the agent (12 directions, nearest to the reference's first), then two rings
        farther out (24 directions) whose straight line from the agent must also pass clear of every body. A
        spot must be within ``r_c`` of the reference, clear of walls along the way and clear of every body.
        """
        sw = self.swarm
        p = sw.xy[agent]
        ref = sw.xy[toward]
        r = self.router_model.radius
        gap = sw.radius[agent] + r + self.params.release_gap
        base = np.arctan2(ref[1] - p[1], ref[0] - p[0])
        others = np.delete(np.arange(len(sw)), agent)
        turns = np.array([0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6]) * (np.pi / 6)
        cand = p + gap * np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
        within = self.r_c if self.drop_rule.near_reference else np.inf
        ok = np.linalg.norm(cand - ref, axis=1) <= within
        ok &= self.path_clear(np.repeat(p[None], len(cand), axis=0), cand, np.full(len(cand), r))
        if len(others):
            d = np.linalg.norm(cand[:, None, :] - sw.xy[None, others, :], axis=2)
            ok &= (d >= r + sw.radius[others][None, :]).all(axis=1)
        hit = np.flatnonzero(ok)
        if len(hit):
            return cand[hit[0]]
        # farther out: the agent's own ring is full (other bodies, walls)
        turns = np.concatenate([[0.0], np.repeat(np.arange(1, 12), 2) * np.array([1.0, -1.0] * 11), [12.0]]) * (
            np.pi / 12)
        step = 2.0 * r + self.params.release_gap
        dirs = np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
        cand = np.concatenate([p + (gap + k * step) * dirs for k in (1, 2)])
        ok = np.linalg.norm(cand - ref, axis=1) <= within
        ok[ok] &= self.path_clear(np.repeat(p[None], int(ok.sum()), axis=0), cand[ok], np.full(int(ok.sum()), r))
        if len(others) and ok.any():
            ok[ok] &= _segments_clear(p, cand[ok], r, sw.xy[others], sw.radius[others])
        hit = np.flatnonzero(ok)
        return cand[hit[0]] if len(hit) else None

    def _add_router(self, agent: int, toward: int, state: int) -> int | None:
        """Release a router from ``agent`` next to itself toward ``toward``; its index, or ``None`` (no free spot)."""
        sw = self.swarm
        spot = self._release_spot(agent, toward)
        if spot is None:
            return None
        new = sw.extend(self.router_model, Role.ROUTER, state, spot[None], np.array([sw.status[agent]]),
                        heading=np.array([sw.heading[agent]]))
        self._grow(len(new))
        self._nodes_changed()
        self.left[agent] -= 1
        self.released += 1
        self.released_by[np.searchsorted(self.agents, agent)] += 1
        return int(new[0])

    def _release_reference(self, agent: int, current: int, t: float) -> int | None:
        """Put a reference router down (settling first for ``settle_s`` when set); its index, ``None``: no free spot.

        Under a rule whose routers drive on to a goal (``strip-goals``) it starts for its goal, once settled.
        """
        new = self._add_router(agent, current, State.REFERENCE if self.settle_s <= 0 else State.DROPPED)
        if new is None:
            return None
        if self.settle_s > 0:
            self.settle_at[new] = t + self.settle_s
            if self.strips is not None:
                self.strips.waiting[new] = current
        elif self.strips is not None:
            self.strips.start(new, current)
        return new

    def _release_triangle(self, agent: int, ref_i: int, ref_j: int) -> None:
        sw = self.swarm
        new = self._add_router(agent, ref_i, State.TRIANGLE)
        if new is None:
            return  # no free spot next to the agent: the pair is not served yet, tried again next step
        key = _pair_key(agent, ref_i, ref_j)
        self._served.add(key)
        self.triangles_released.append(key)
        self.moving_triangles += 1
        goal = triangle_goal(sw.xy[[ref_i]], sw.xy[[ref_j]], sw.xy[[agent]], self.r_eff)
        self.steering.start(np.array([new]), goal, np.array([[ref_i, ref_j]]))
        if self.params.triangular == "local":
            self.disabled[[new, ref_i, ref_j]] = True


