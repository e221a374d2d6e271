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
* Under a radio whose links are not decided by distance alone (walls, shadowing, packet loss), a triangle router
  settles only where its table row holds one of its references, or else drives back to where it last heard one
  (:mod:`amronet.algorithms.agent_assisted.movers`).

The controller is split by responsibility: its parameters (:mod:`.params`), releasing routers (:mod:`.releases`),
the drop rule's view and the realism switches (:mod:`.drop_switches`) and the released routers that move
(:mod:`.movers`) are mixed into :class:`AgentAssisted` here.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.drop_switches import DropSwitches
from amronet.algorithms.agent_assisted.drops import DROP_RULES, DropContext, validate_drop_params
from amronet.algorithms.agent_assisted.drops.trail import Trails
from amronet.algorithms.agent_assisted.explorers import EXPLORERS, Explorer, PathFollower
from amronet.algorithms.agent_assisted.kernels import track_agents
from amronet.algorithms.agent_assisted.movers import Movers
from amronet.algorithms.agent_assisted.params import DEFAULT_COVERAGE_TARGET, AgentAssistedParams
from amronet.algorithms.agent_assisted.releases import Releasing, _pair_key
from amronet.algorithms.agent_assisted.relocate import Relocator
from amronet.algorithms.agent_assisted.retrace import Retracer
from amronet.algorithms.agent_assisted.strip_driving import StripDrivers
from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput
from amronet.algorithms.common.goto import GoalSteering
from amronet.algorithms.common.references import check_loss_band
from amronet.algorithms.common.triangular import select_triangles
from amronet.algorithms.stepping import FastStep, StepContext
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError

__all__ = ["DEFAULT_COVERAGE_TARGET", "AgentAssisted", "AgentAssistedParams", "_pair_key"]


@ALGORITHMS.register("agent-assisted")
class AgentAssisted(Releasing, DropSwitches, Movers, Controller):
    """Controller of agents that carry and release routers."""

    Params = AgentAssistedParams
    params: AgentAssistedParams
    default_coverage_target = DEFAULT_COVERAGE_TARGET

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
        self.triangles_cut_off = 0
        """Triangle routers that settled hearing neither reference (the link test at settling, :mod:`.movers`)."""
        self.nearest_d = np.empty(len(self.agents))
        """Per agent, the distance to its nearest reference in range, as the last tracking found it."""
        self.other_ref = np.empty(len(self.agents), dtype=np.int64)
        """Per agent, its nearest reference of another status (-1: none), as the last tracking found it."""
        self._deployed: np.ndarray | None = None
        self._deployed_xy: np.ndarray | None = None
        self.triangles_released: list[tuple[int, int, int]] = []
        """Every triangle release as ``(agent, reference, reference)``, the references in increasing order."""
        self._served: set[tuple[int, int, int]] = set()
        self._served_rows: tuple[int, np.ndarray] = (-1, np.zeros((0, 3), dtype=np.int64))
        """:meth:`served_pairs` as last built, and the size of ``_served`` then (it only grows)."""
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
        self.relocator: Relocator | None = None
        if self.params.repair == "relocate":
            self.relocator = Relocator(n, self.params.repair_confirm_s, self.params.give_up_steps)
        elif self.params.repair == "retrace":
            on_path = None if setup.paths is None else np.diff(setup.paths.start)[:len(self.agents)] > 0
            self.relocator = Retracer(n, self.params.repair_confirm_s, self.params.give_up_steps, self.agents, sw,
                                      self.router_model.radius, step, on_path)
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
        self.steering.grow(n_new)
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
        """The triangles served so far as rows ``(agent, lower reference, higher reference)`` ``(k, 3)`` int64.

        Kept until a triangle is served (the set only grows); the caller must not write to it.
        """
        if self._served_rows[0] != len(self._served):
            self._served_rows = (len(self._served), np.array(sorted(self._served), dtype=np.int64).reshape(-1, 3))
        return self._served_rows[1]

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
            reversing = self.reversing.any()  # (releasing a router does not change it)
            if reversing:
                drop = self._reverse_drops(view, drop)
            droppers = np.asarray(drop).nonzero()[0]  # (np.flatnonzero's cost thrice over, on a few agents)
            dropped = np.zeros(len(agents), dtype=bool) if len(droppers) else None
            for m in droppers:
                toward = self._toward(m, view)
                new = self._release_reference(int(agents[m]), toward, step.t) if toward >= 0 else None
                if new is not None:
                    assert dropped is not None
                    dropped[m] = True
                    if losing[m] and sw.state[new] == State.STRIP:  # it drives off (strip-goals): wait for one to stay
                        if held is None:
                            held = np.zeros(len(agents), dtype=bool)
                        held[m] = True
                elif losing[m]:
                    if held is None:
                        held = np.zeros(len(agents), dtype=bool)
                    held[m] = True  # no free spot to put a router down: turn back as a tethered agent does
            if dropped is not None and dropped.any():
                self.drop_rule.dropped(dropped, view)
                if self.settle_s > 0:
                    self.pending_until[dropped] = step.t + self.settle_s
                if reversing:
                    self.reverse_drops += int(np.count_nonzero(dropped & self.reversing))
                    self.reversing &= ~dropped

        # agents: explore, or turn back when tethered (no router left and about to lose the last reference)
        scans = step.readings.of(agents, self.agent_model)
        sensor_range = sw.models[self.agent_model].sensor_range
        self.explorer.steer(sw.heading, agents, scans, sensor_range, self.refused[agents], self.rng, sw.xy,
                            self.deployed_nodes()[1])
        if losing is not None:
            assert view is not None
            if self.tether:
                tethered = losing & (self.left[agents] < 1)
                if held is not None:
                    tethered |= held
            else:
                tethered = held  # (None: no agent turns back)
            for m in () if tethered is None else tethered.nonzero()[0]:
                toward = self._toward(m, view)
                if toward >= 0:
                    back = sw.xy[toward] - sw.xy[agents[m]]
                    sw.heading[agents[m]] = np.arctan2(back[1], back[0])
        if self.trails is not None:
            self._back_up(view)
        return self.movers_command(step, n_before)

    def mission_report(self) -> dict[str, object]:
        """Relays used and who put them down, the drop rule and what it counted (the summary's ``mission``)."""
        out: dict[str, object] = {"drop_rule": self.params.drop_rule, "relays_used": int(self.released),
                                  "released_per_agent": [int(k) for k in self.released_by],
                                  "triangle_relays": len(self.triangles_released)}
        if self.triangles_cut_off:
            out["triangle_relays_cut_off"] = self.triangles_cut_off
        if self.reverse_after_s is not None:
            out["reverse_drops"] = self.reverse_drops
        if self.relocator is not None:
            out["relocations"] = self.relocator.moves
        if isinstance(self.relocator, Retracer):
            out["retrace_points_skipped"] = self.relocator.skipped
        if self.strips is not None:
            out["strip_goals"] = dict(self.strips.counts)
        out.update(self.drop_rule.report())
        out.update(self.explorer.report())
        return out

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        self.refused[:] = False
        self.refused[movers] = refused
