"""The routers' side of a loop of one or more self-spreading runs: commands in, observations and rewards out.

Shared by the PettingZoo router environment (one run, :mod:`amronet.env.routers`) and its vectorised variant (a
:class:`~amronet.sim.batch.BatchSimulation` of many seeds, :mod:`amronet.env.vector`). A router acts while it is
unsettled (exploring, or driving to a triangle's goal point: then the controller steers it and its action is not
read); it is terminated when it settles. Reward of router ``r`` after a step (weights
:class:`~amronet.env.config.RewardWeights`)::

    coverage x (connected coverage of its run gained this step)   shared by its run's routers
  - cut_off  x dt                                                   if r has no path to a base station after the step
  - router   x 1                                                    if r settled this step

A run ends when its routers have all settled or its coverage reaches the target (``sim.coverage_target``; none
when not set): every router still acting is terminated. At ``max_steps`` they are truncated.
"""

from __future__ import annotations

import numpy as np

from amronet.engine.network import connected_to
from amronet.engine.robots import SETTLING_STATES, Role, State
from amronet.env.config import EnvConfig
from amronet.env.observe import Observer
from amronet.sim.loop import Loop
from amronet.sim.run import metrics_of

__all__ = ["ROUTER_FLAGS", "RouterCore"]

ROUTER_FLAGS = ("connected", "triangle")
"""A router's flags: it has a path to a base station; the controller drives it to a triangle's goal point."""


class RouterCore:
    """The routers of the ``G`` runs of ``loop``, ``R`` per run, as ``(G, R)`` arrays.

    Args:
        loop: A loop of self-spreading runs whose scenario has the ``external`` stop rule (and walk, with
            ``motion: policy``).
        config: The environment's configuration.
        max_steps: Truncation step.
    """

    def __init__(self, loop: Loop, config: EnvConfig, max_steps: int) -> None:
        self.loop = loop
        self.config = config
        self.max_steps = max_steps
        sw = loop.swarm
        blocks = [run.robots for run in loop.runs]
        self.ids = np.stack([np.flatnonzero(sw.rows(b).role == Role.ROUTER) + (b.start or 0) for b in blocks])
        """Global index of router ``r`` of run ``g`` ``(G, R)``."""
        self.start = sw.xy[self.ids].copy()
        model = sw.models[int(sw.model[self.ids.flat[0]])]
        self.observer = Observer(loop.world.omap, model.sensor_beams, model.sensor_range, loop.medium.reach,
                                 loop.medium.budget.threshold_dbm, ROUTER_FLAGS, False, config, self.ids.size)
        self.bases = np.flatnonzero(sw.role == Role.BASE)
        self.live = np.ones(self.ids.shape, dtype=bool)
        """Which routers still act (not settled, their run not over)."""
        self.running = np.ones(len(blocks), dtype=bool)
        self.blocks = np.array([(b.start or 0, len(sw) if b.stop is None else b.stop) for b in blocks], dtype=np.int64)
        """First and past-the-last robot of each run ``(G, 2)``."""
        self.targets = np.array([np.inf if run.coverage_target is None else run.coverage_target for run in loop.runs])
        """Each run's coverage target (``inf``: none)."""
        self.steps = 0
        self._linked_of: tuple[object, np.ndarray, np.ndarray] | None = None
        self.coverage = self._coverages(np.ones(len(blocks), dtype=bool))[1]
        self.live &= self._unsettled()

    def _unsettled(self) -> np.ndarray:
        return self.loop.swarm.in_states(SETTLING_STATES)[self.ids]

    def _linked_all(self) -> tuple[np.ndarray, np.ndarray]:
        """``(relays, linked)`` ``(N,)``: which robots relay, which have a path to a base station through them.

        Searched once per table (and set of relays).
        """
        loop = self.loop
        relaying = loop.swarm.relaying
        cached = self._linked_of
        if cached is None or cached[0] is not loop.table or not np.array_equal(cached[1], relaying):
            cached = self._linked_of = (loop.table, relaying, connected_to(loop.table, self.bases, relaying))
        return cached[1], cached[2]

    def _linked(self) -> np.ndarray:
        return self._linked_all()[1][self.ids]

    def _coverages(self, running: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(coverage, connected coverage)`` ``(G,)`` of the runs ``running`` now (the others' entries are 0).

        What :func:`~amronet.sim.run.metrics_of` gives, without what the reward does not read (components, routers):
        a batch's coverages in one compiled call (no link joins two runs, so one search from every base station
        serves them all), otherwise run by run.
        """
        loop = self.loop
        out = np.zeros((len(running), 2))
        if not running.any():
            return out[:, 0], out[:, 1]
        fractions = None
        if loop.groups is not None:
            relaying, linked = self._linked_all()
            blocks = self.blocks if running.all() else self.blocks[running]
            fractions = loop.medium.run_coverages(loop.world.coverage, loop.swarm.xy, relaying, linked, blocks,
                                                  loop.scenario.sim.coverage_method)
        if fractions is None:
            runs = [loop.runs[g] for g in np.flatnonzero(running)]
            fractions = [(m.coverage, m.connected_coverage) for m in metrics_of(runs)]
        out[running] = fractions
        return out[:, 0], out[:, 1]

    def observe(self) -> dict[str, np.ndarray]:
        """Every router's observation, stacked ``(G * R, ...)`` (run by run)."""
        loop = self.loop
        sw = loop.swarm
        ids = self.ids.reshape(-1)
        flags = np.stack([self._linked().reshape(-1), sw.state[ids] == State.TRIANGLE], axis=1)
        return self.observer.observe(sw.xy, sw.heading, sw.radius, loop.table, sw.deployed, ids,
                                     self.start.reshape(-1, 2), flags)

    def step(self, turn: np.ndarray, speed: np.ndarray, wish: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """One step of every run with the routers' commands ``(G, R)`` (those of routers not acting are not read).

        Returns:
            ``(rewards, terminated, truncated, acted)`` ``(G, R)``: ``acted`` marks the routers that acted this step
            (the others' entries are 0 / ``False``).
        """
        loop = self.loop
        external = loop.controller.external
        n = len(loop.swarm)
        t, s, w = np.zeros(n), np.zeros(n), np.zeros(n, dtype=bool)
        acted = self.live.copy()
        t[self.ids[acted]], s[self.ids[acted]], w[self.ids[acted]] = turn[acted], speed[acted], wish[acted]
        external.command(t, s, w)
        loop.step()
        self.steps += 1
        coverage, connected = self._coverages(self.running)
        cov = np.where(self.running, connected, self.coverage)
        reached = self.running & (coverage >= self.targets)
        gained = cov - self.coverage
        self.coverage = cov
        unsettled = self._unsettled()
        settled_now = acted & ~unsettled
        wt = self.config.reward
        rewards = (wt.coverage * gained[:, None] - wt.cut_off * loop.dt * (~self._linked())
                   - wt.router * settled_now)
        rewards = np.where(acted, rewards, 0.0)
        still = acted & unsettled
        over = reached | ~still.any(axis=1)
        terminated = acted & (~unsettled | over[:, None])
        truncated = acted & ~terminated & (self.steps >= self.max_steps)
        self.live = acted & ~terminated & ~truncated
        self.running &= self.live.any(axis=1)
        return rewards, terminated, truncated, acted
