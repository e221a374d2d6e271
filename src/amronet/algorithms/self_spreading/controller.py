"""Self-spreading (paper section 4.2, with the triangular deployment and optimizations of 4.3).

Routers start at the base stations with status -1 in state *explore* and random-walk with obstacle avoidance.
Each keeps a current reference (a base node or deployed router it hears). A router that is **about to lose its last
reference** stops, becomes a *reference* and takes the status of its current reference. A router whose current
reference has status ``i`` that hears a reference of status ``p != i`` goes into *triangle* state with status ``i``
and moves to a point that keeps both references linked (:mod:`amronet.algorithms.common.triangular`).

**Walks** (``walk``): how exploring routers move — ``random`` (the paper's, the default), ``straight`` (a persistent
walk), ``growth`` (toward where the network grows, along the routing's growth field) or ``guided`` (``growth``'s way
there, the random walk at the frontier); see :mod:`amronet.algorithms.self_spreading.walks`.

**Stop rules** (``stop_rule``). ``distance`` (the paper's, the default): the current reference is kept while it is
within ``r_c`` and otherwise the nearest reference is taken; a router stops when every reference it hears is at
least ``(1 - loss_margin) r_c`` away. ``link-quality`` (location-free, paper sections 6-7): a router reads only the
margins of its links (dB above the usable threshold, :attr:`~amronet.engine.table.NeighbourTable.margin`) and its own
state. Its current reference is kept while it is heard and otherwise the strongest one is taken; it keeps an
exponential moving average (time constant ``smoothing_s``, restarted when it hears no reference) of its best margin
to any reference, and stops when the smoothed margin is below ``stop_margin_db``, or at once when the raw best margin
is below ``loss_margin_db`` (hysteresis: one faded sample does not stop it, a link about to break does).

**Triangle rules** (``triangle_rule``). ``geometric`` (the paper's, the default): drive to the triangular goal point
at ``(1 - loss_margin) r_c`` from both references; settle there, or earlier when blocked for ``give_up_steps`` steps
in a row, or when a move would take it farther than ``(1 - loss_margin) r_c`` from either reference. Ours, for
radios whose links are not decided by distance alone (walls, shadowing, packet loss:
:attr:`~amronet.algorithms.base.Setup.links_by_distance` is false), the *link test at settling*: the router settles
only where its own table row holds one of its two references
(:meth:`~amronet.algorithms.common.goto.GoalSteering.check_links`); otherwise it drives back to where it last heard
one (no metre rule on the way) and settles there if it hears one; if not, it explores again, as under the
``link-quality`` rule. Under the unit disk the metre rule keeps both links and the test is skipped. ``link-quality``
("routers deployed during the triangular deployment move in the direction where the link quality tends to be weak",
paper section 6.3) is a run-and-tumble (chemotaxis) search that reads only the margins ``m_i``, ``m_j`` of the
router's links to its two references ``R_i``, ``R_j``: with ``m_s = stop_margin_db`` and
``f = (m_i - m_s)^2 + (m_j - m_s)^2``, the router keeps its heading while ``f`` decreases from one step to the next
and otherwise (or when its move was refused) turns to a fresh uniform heading drawn from the run's generator, with the
random walk's obstacle avoidance; a step that lost a link it heard is undone (it turns around). It settles when both
margins are within ``triangle_tolerance_db`` of ``m_s`` (both links as strong as a greedy stop leaves them), where it
is when a margin falls below ``loss_margin_db`` (having been at or above it the step before), when ``f`` has not
reached a new low for ``give_up_steps`` steps (the references are too far apart for both links to reach ``m_s``: it
settles near the best point found), or after ``triangle_max_s`` seconds. A triangle router that hears neither
reference when it would settle goes back to exploring instead (it would be cut off).

Everything a router decides comes from its own range readings and its own row of the neighbour table:
distances (``distance`` rules) or link margins (``link-quality`` rules) to the nodes it hears and what they announce
(state, status, the local-rule flag, position for the geometric triangle goal). The ``global`` rule additionally
asks the deployed network whether two components are already joined, which is the paper's global-communication
strategy. Whether a triangle is needed at all (are its two references more than ``r_c`` apart?) is still decided
from the references' announced positions under either triangle rule
(:func:`~amronet.algorithms.common.triangular.select_triangles`); the ``link-quality`` rules make a router's own stops
and
moves position-free, not that check.

Why ``loss_margin`` default 0.05: a router moves at most ``max_speed * dt`` per step and must not cross the band
``[(1 - loss_margin) r_c, r_c]`` in one step, or it would lose its reference before noticing. With the Bebot
defaults (0.2 m/s, dt 0.1 s) one step is 0.02 m, well inside the 0.05 m band at ``r_c`` = 1 m. The band is
checked against the step length when a run starts.

Why ``stop_margin_db`` 3, ``loss_margin_db`` 1 and ``smoothing_s`` 0.5 by default: every radio model reports a margin
(the unit disk reports the log-distance margin ``10 n log10(r_c / d)`` without walls or shadowing,
:mod:`amronet.engine.radio`), so the rule runs unchanged under all of them. Without walls it stops at
``d = r_c 10^(-stop_margin_db / (10 n))``: 0.76 ``r_c`` under the unit disk and ``log-distance`` (``n`` = 2.5 by
default) and 0.71 ``r_c`` under ``multi-wall`` (``n`` = 2.0), against 0.95 ``r_c`` for the distance rule; the loss
threshold sits at 0.91 ``r_c`` (unit disk) and 0.89 ``r_c`` (multi-wall). The moving average lags behind a router
driving straight out, so with smoothing a router stops between those two distances (at most about ``smoothing_s``
times the margin's rate of change late: 1.4 dB at 0.2 m/s and ``r_c`` = 1 m). Measured on ``self-spreading-6x6`` (unit
disk, seed 1), the distance from a new reference to the nearest earlier one: 0.76-0.78 ``r_c`` with ``smoothing_s`` 0,
0.79-0.86 ``r_c`` with 0.5 s. 3 dB leaves a link that delivers 99.96 % of its packets (0.9 at the threshold,
:func:`~amronet.engine.propagation.delivery_ratio`) and room for a few dB of shadowing before the link breaks; 1 dB is
where delivery starts to fall (97.7 %) and still several steps of margin from the threshold (one 0.02 m Bebot step
changes the margin by about 0.24 dB near 0.9 ``r_c``). A wall stepped behind costs 6.9 dB at once (``multi-wall``): no
rule that reads the present margin sees that coming; the router then hears no reference and walks on until it hears
one again. 0.5 s (five steps of 0.1 s) averages out packet-loss flicker of the best link but follows a router's
motion. Routers still start within ``(1 - loss_margin) r_c`` of their base: one that starts beyond the stop distance
stops within a few steps (at once below the loss threshold), linked to the base.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import ALGORITHMS, Command, Controller, Setup, StepInput
from amronet.algorithms.common.goto import GoalSteering
from amronet.algorithms.common.link_quality import MarginSearch, MarginSmoother, anchor_margins, strongest_references
from amronet.algorithms.common.references import check_loss_band, track_references
from amronet.algorithms.common.triangular import select_triangles, triangle_goal
from amronet.algorithms.self_spreading.external import EXTERNAL, ExternalCommands
from amronet.algorithms.self_spreading.params import SelfSpreadingParams
from amronet.algorithms.self_spreading.walks import Walker
from amronet.algorithms.stepping import FastStep, StepContext
from amronet.engine.motion import random_walk
from amronet.engine.robots import SETTLING_STATES, Role, State, state_lookup

__all__ = ["SelfSpreading", "SelfSpreadingParams"]


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
        p = self.params
        routers = sw.role == Role.ROUTER
        step = float(sw.max_speed[routers].max(initial=0.0)) * self.dt
        self.r_eff = check_loss_band(p.loss_margin, self.r_c, step, "router")
        self.current = np.full(n, -1, dtype=np.int64)
        self.steering = GoalSteering(n, n_anchors=2, give_up_steps=p.give_up_steps)
        self.disabled = np.zeros(n, dtype=bool)
        self.refused = np.zeros(n, dtype=bool)
        walk = "random" if p.walk == EXTERNAL else p.walk  # (an external walk never asks its walker)
        self.walker = Walker(walk, n, self.r_c, p.turn_noise * np.sqrt(self.dt), p.growth_s, p.follow_steps)
        self.external = (ExternalCommands(n, "algorithm.params.walk" if p.walk == EXTERNAL
                                          else "algorithm.params.stop_rule")
                         if EXTERNAL in (p.walk, p.stop_rule) else None)
        """The commands of a policy outside (:mod:`.external`), or ``None``."""
        self.router_model = int(sw.model[routers][0]) if routers.any() else 0
        self.several_statuses = len(np.unique(sw.status[sw.role == Role.BASE])) > 1
        self.by_signal = p.stop_rule == "link-quality"
        self.searching = p.triangle_rule == "link-quality"
        self.smoother = MarginSmoother(n, self.dt, p.smoothing_s) if self.by_signal else None
        self.search = (MarginSearch(n, p.stop_margin_db, p.triangle_tolerance_db, p.loss_margin_db, p.give_up_steps,
                                    p.triangle_max_s) if self.searching else None)

    @classmethod
    def start_range(cls, params: SelfSpreadingParams, r_c: float) -> float:  # noqa: D102
        return (1.0 - params.loss_margin) * r_c

    def unsettled(self) -> np.ndarray:  # noqa: D102
        return self.swarm.in_states(SETTLING_STATES)

    def settling_rule(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`unsettled` for compiled callers: ``(lookup, robots)``, unsettled where ``lookup[state] & robots``."""
        return state_lookup(SETTLING_STATES), np.ones(len(self.swarm), dtype=np.bool_)

    def fast_step(self, context: StepContext) -> FastStep | None:
        """The compiled sense, decide and move (:class:`.fast.CompiledSpreading`) where it applies."""
        from amronet.algorithms.self_spreading.fast import CompiledSpreading  # (its kernels load with it)

        return CompiledSpreading(self, context) if CompiledSpreading.applies(self, context) else None

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw = self.swarm
        if self.external is not None:
            self.external.check()
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
        everyone = len(w) == len(movers)
        if self.external is not None and self.params.walk == EXTERNAL:
            speed[walking] = self.external.steer(sw.heading, w, speed[walking])
        else:
            self.walker.steer(sw.heading, w, scans if everyone else scans[walking], sensor_range, self.refused[w],
                              self.rng, step.table, sw.xy, sw.deployed if self.walker.reads_network else None, step.t)
        tri = movers[~walking]
        if len(tri):
            if self.searching:
                speed[~walking] = self._search_triangles(step, tri, scans[~walking], sensor_range)
            else:
                speed[~walking] = self._steer_triangles(step, tri, scans[~walking], sensor_range)
        return Command(movers, speed)

    def _decide_explorers(self, step: StepInput, explorers: np.ndarray) -> None:
        sw = self.swarm
        is_ref = sw.deployed
        want_other = self.several_statuses and self.params.triangular != "off"
        if self.by_signal:
            links = strongest_references(step.table, explorers, self.current[explorers], is_ref, sw.status,
                                         want_other=want_other)
            current, other, has_reference = links.current, links.other, links.has_reference
            about_to_lose = self._weak_links(explorers, links.best_margin)
        else:
            view = track_references(step.table, explorers, self.current[explorers], is_ref, sw.status,
                                    want_other=want_other)
            current, other, has_reference = view.current, view.other, view.has_reference
            if self.external is not None and self.params.stop_rule == EXTERNAL:
                about_to_lose = self.external.wishes(explorers)
            else:
                about_to_lose = view.nearest_distance >= self.r_eff
        self.settle_explorers(step, explorers, current, other, has_reference, about_to_lose)

    def settle_explorers(self, step: StepInput, explorers: np.ndarray, current: np.ndarray, other: np.ndarray,
                         has_reference: np.ndarray, about_to_lose: np.ndarray) -> None:
        """What the exploring robots do with what they found this step (arrays aligned with ``explorers``).

        They keep ``current`` as their references; those that met a reference of another status (``other``)
        start the triangular deployments the rule allows; the others that hear a reference and are about to lose
        it stop and become references. Shared by the reference step and the compiled one
        (:mod:`amronet.algorithms.self_spreading.fast`), which calls it when a triangular deployment may start.
        """
        sw = self.swarm
        self.current[explorers] = current

        triangles = np.zeros(len(explorers), dtype=bool)
        if self.params.triangular != "off":
            cand = np.flatnonzero(other >= 0)
            if len(cand):
                committed = sw.deployed | (sw.state == State.TRIANGLE)
                go = select_triangles(
                    self.params.triangular, explorers[cand], current[cand], other[cand], sw.xy,
                    self.r_c, self.disabled, step.table, committed,
                )
                triangles[cand[go]] = True
        if triangles.any():
            who = explorers[triangles]
            ref_i, ref_j = current[triangles], other[triangles]
            sw.state[who] = State.TRIANGLE
            sw.status[who] = sw.status[ref_i]
            if self.search is not None:
                self.search.start(who, np.stack([ref_i, ref_j], axis=1), step.t)
            else:
                goal = triangle_goal(sw.xy[ref_i], sw.xy[ref_j], sw.xy[who], self.r_eff)
                self.steering.start(who, goal, np.stack([ref_i, ref_j], axis=1))
            if self.params.triangular == "local":
                self.disabled[np.concatenate([who, ref_i, ref_j])] = True

        losing = has_reference & about_to_lose & ~triangles
        who = explorers[losing]
        sw.state[who] = State.REFERENCE
        sw.status[who] = sw.status[current[losing]]

    def _weak_links(self, explorers: np.ndarray, best_margin: np.ndarray) -> np.ndarray:
        """The ``link-quality`` stop rule: which explorers' best reference margins ``(M,)`` are about to be lost.

        Reads the margins and the explorers' own moving averages only (updated here, once per step).
        """
        assert self.smoother is not None
        p = self.params
        smoothed = self.smoother.update(explorers, best_margin)
        with np.errstate(invalid="ignore"):  # nan (nothing heard) compares False
            return (smoothed < p.stop_margin_db) | (best_margin < p.loss_margin_db)

    def _steer_triangles(self, step: StepInput, tri: np.ndarray, scans: np.ndarray,
                         sensor_range: float) -> np.ndarray:
        """The geometric triangle rule: one go-to-goal step of the triangle routers ``tri``; their speeds.

        Where links are not decided by distance alone, a router settles only where its table row holds one of its
        references (:meth:`~amronet.algorithms.common.goto.GoalSteering.check_links`); one lost goes back to exploring.
        """
        sw = self.swarm
        length, done = self.steering.steer(tri, sw.xy, sw.heading, scans, sensor_range,
                                           sw.max_speed[tri] * self.dt, self.r_eff)
        if not self.links_by_distance:
            done, lost = self.steering.check_links(tri, done, step.table, sw.xy)
            self._back_to_exploring(tri[lost])
        sw.state[tri[done]] = State.TRIANGLE_SETTLED
        return length / self.dt

    def _back_to_exploring(self, lost: np.ndarray) -> None:
        """Triangle routers that would settle out of touch with both references explore again, with no reference."""
        sw = self.swarm
        sw.state[lost] = State.EXPLORE
        sw.status[lost] = -1
        self.current[lost] = -1
        if self.smoother is not None:
            self.smoother.restart(lost)

    def _search_triangles(self, step: StepInput, tri: np.ndarray, scans: np.ndarray,
                          sensor_range: float) -> np.ndarray:
        """The ``link-quality`` triangle rule: one run-and-tumble step of the triangle routers ``tri``; their speeds."""
        sw = self.swarm
        assert self.search is not None
        margins = anchor_margins(step.table, tri, self.search.anchors[tri])
        tumble, reverse, done = self.search.step(tri, margins, step.t)
        go = ~done
        back = tri[go & reverse]
        sw.heading[back] = np.remainder(sw.heading[back], 2.0 * np.pi) - np.pi  # turned around
        random_walk(sw.heading, tri[go], scans[go], sensor_range, tumble[go] | self.refused[tri[go]], self.rng, 0.0)
        cut_off = done & ~np.isfinite(margins).any(axis=1)
        sw.state[tri[done & ~cut_off]] = State.TRIANGLE_SETTLED
        self._back_to_exploring(tri[cut_off])  # settled here, it would hear neither reference
        return np.where(done, 0.0, sw.max_speed[tri])

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        self.refused[:] = False
        self.refused[movers] = refused
        if self.searching or not self.links_by_distance:  # (then one that arrived settles by its next table)
            return
        tri = movers[self.swarm.state[movers] == State.TRIANGLE]
        arrived = np.linalg.norm(self.swarm.xy[tri] - self.steering.goal[tri], axis=1) <= 1e-9
        self.swarm.state[tri[arrived]] = State.TRIANGLE_SETTLED
