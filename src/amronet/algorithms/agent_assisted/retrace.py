"""``repair: retrace`` — a router that a failure cut off backs up the way it came until its routing finds a base.

The relocation repair (:mod:`.relocate`) sends a cut-off router straight toward where its lost neighbour stood.
Behind walls that spot may hear nobody, and the straight way there may lead into a room whose walls cut the link the
move was meant to make. This rule moves the same routers at the same moment, but along a way that is known to be
drivable and known to have been in contact with the network: the way the router came in.

* **The way in** (odometry breadcrumbs, :mod:`.breadcrumbs`). Every agent keeps its own path as points sampled from
  its odometry, with loops erased: a point that comes within :attr:`Breadcrumbs.erase` of an earlier point of the
  path cuts the path back to that earlier point (a loop-erased walk). When an agent puts a router down it hands it
  its path (the router was carried along it); a router that then drives on (a triangle router, a strip router) adds
  its own steps. The points are one tree shared by all (a point keeps its predecessor), so a router holds only the
  point it came from.
* **Drivable**: the agent's body was free at every point, and two points of the path are at most
  ``2 (r_agent - r_router)`` apart (the sampling, and the erasing radius), so a router, smaller than the agent, can
  drive straight from one to the next: every point of that segment is within ``r_agent - r_router`` of an end.
  Routers that stand in the way are avoided with the range sensors as on any go-to-goal move; a point the router
  cannot reach in ``give_up_steps`` steps is skipped.
* **In contact**: under a drop rule that keeps the agents connected (``link-quality`` behind walls, the paper's rule
  on the unit disk), the agent heard a reference at every point of its way, and the way begins at its base station.
  Retracing it, the router comes back into range of the part of the network that still has a path to a base, at
  the latest at the base station itself.
* **Who moves, when it stops**: as in :mod:`.relocate`: a deployed router (a reference or settled triangle router)
  that has lost a neighbour for ``repair_confirm_s`` and has no path to a base station any more; it stops as soon as
  its routing has a path again (the first point of its way back where it hears the connected network), at the start
  of its way, or after skipping :data:`MAX_SKIPS` points in a row. A router that loses its link to one that moved
  away, and is cut off, backs up in turn (the cascade).
* **One at a time**: a router due to move waits while it hears a neighbour that backs up (state ``relocating``,
  which it announces), or one that starts to this step (the lower id goes first). A cut-off group that hears one
  another sends one router back, and the others reconnect through it when it does; one that loses it (it moved
  out of range) and is still cut off goes next. Without it the whole group backed up side by side, each as far as
  the first.

Sources: MARBLE's *reverse drop* (DARPA SubT; ``../shared/reference/drop-rules.md``): an agent out of contact backs
up along its own path until contact returns; RIM and DARA (survey of Younis, Senturk, Akkaya, Lee, Senel, *Computer
Networks* 58 (2014) 254-283) for who moves (the failed node's neighbours, cascaded moves) and DARA's concern that
connected nodes stay put. Ours: a router inherits the path of the agent that carried it, the loop erasure with a
radius that keeps every segment drivable, applying reverse drop to deployed routers as a repair, and one mover
at a time among routers that hear one another.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.breadcrumbs import Breadcrumbs
from amronet.algorithms.agent_assisted.relocate import Relocator
from amronet.engine.radio import NeighbourTable
from amronet.engine.robots import Role, State, Swarm, state_lookup
from amronet.errors import ScenarioError

__all__ = ["MAX_SKIPS", "Breadcrumbs", "Retracer"]

MAX_SKIPS = 5
"""A retracing router that has skipped this many points of its way in a row (each blocked) stops."""

_SELF_DRIVEN = state_lookup((State.TRIANGLE, State.STRIP))
"""States of routers that drive on their own after release (their steps are added to their way)."""
_MOVABLE = state_lookup((State.REFERENCE, State.TRIANGLE_SETTLED))


class Retracer(Relocator):
    """The retracing repair's state (see the module docstring): :class:`.Relocator`'s losses, another way to go.

    Args:
        n: Number of robots now (grows with :meth:`grow`).
        confirm_s: How long a neighbour must be missing before it counts as lost, seconds.
        give_up_steps: Steps without progress after which a point of the way is skipped.
        agents: Node ids of the agents.
        sw: The robots (the agents' start positions and radii, the routers' model).
        router_radius: Radius of the routers the agents carry, metres.
        agent_step: Farthest an agent moves in one step, metres.
        on_path: Which agents follow a given path (they never back up); default none.
    """

    def __init__(self, n: int, confirm_s: float, give_up_steps: int, agents: np.ndarray, sw: Swarm,
                 router_radius: float, agent_step: float, on_path: np.ndarray | None = None) -> None:
        reach = 2.0 * (float(sw.radius[agents].min()) - router_radius)
        if reach <= 0:
            raise ScenarioError("algorithm.params.repair", f"retrace needs routers smaller than the agents that "
                                f"carry them (router radius {router_radius:g} m, agent radius "
                                f"{float(sw.radius[agents].min()):g} m); choose smaller routers.robot or use relocate")
        super().__init__(n, confirm_s, give_up_steps)
        self.agents = agents
        self.crumbs = Breadcrumbs(sw.xy[agents], spacing=max(reach - agent_step, 0.5 * reach), erase=reach)
        self.reach = 0.5 * self.crumbs.spacing
        """A point of the way counts as reached within this distance."""
        self.node = np.full(n, -1, dtype=np.int64)
        """Per router, the point of its way it came from (-1: none)."""
        self.skips = np.zeros(n, dtype=np.int64)
        self.skipped = 0
        """Points skipped, blocked, over the run."""
        self.backing = np.zeros(len(agents), dtype=bool)
        """Agents backing up their own path (cut off for ``confirm_s``)."""
        self.on_path = np.zeros(len(agents), dtype=bool) if on_path is None else on_path
        """Agents that follow a given path (``agents.trajectories``): they keep to it and never back up."""
        self.contact_at = np.zeros(len(agents))
        """When each agent last had a path to a base station."""
        self.agent_backs = 0
        """Times an agent started to back up."""

    def grow(self, n_new: int) -> None:  # noqa: D102
        super().grow(n_new)
        self.node = np.concatenate([self.node, np.full(n_new, -1, dtype=np.int64)])
        self.skips = np.concatenate([self.skips, np.zeros(n_new, dtype=np.int64)])

    def carried(self, router: int, agent: int, sw: Swarm) -> None:
        """``agent`` put ``router`` down: the router keeps the agent's path, from where the agent stands now."""
        m = int(np.searchsorted(self.agents, agent))
        self.node[router] = self.crumbs.extend(m, sw.xy[agent])

    def update(self, t: float, table: NeighbourTable, sw: Swarm) -> tuple[np.ndarray, np.ndarray]:
        """Record the agents' and self-driven routers' odometry (:meth:`odometry`), then :meth:`.Relocator.update`."""
        self.odometry(sw)
        return super().update(t, table, sw)

    def odometry(self, sw: Swarm) -> None:
        """Record the agents' and self-driven routers' odometry: the agents not backing up, from where they are."""
        self.crumbs.record(sw.xy[self.agents], ~self.backing)
        driving = np.flatnonzero(_SELF_DRIVEN[sw.state])
        if len(driving):
            driving = driving[self.node[driving] >= 0]
            at = self.crumbs.xy[self.node[driving]]
            xy = sw.xy[driving]
            driving = driving[np.hypot(xy[:, 0] - at[:, 0], xy[:, 1] - at[:, 1]) > 1e-9]
            self.node[driving] = self.crumbs.add_many(sw.xy[driving], self.node[driving])

    def _movable(self, routers: np.ndarray, sw: Swarm) -> np.ndarray:
        """Deployed routers (references and settled triangle routers) that know the way they came."""
        return (sw.role[routers] == Role.ROUTER) & _MOVABLE[sw.state[routers]] & (self.node[routers] >= 0)

    def _choose(self, due: np.ndarray, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        """One mover at a time: a router waits while it hears a neighbour that backs up, or one that starts now.

        The due routers are cut off (the aftermath of a failure: few), so they are taken one by one in the order of
        their first due loss; a router that waits at its first loss waits at its others too.
        """
        _, first = np.unique(self._li[due], return_index=True)
        chosen: list[int] = []
        started: list[int] = []
        relocating = sw.state == State.RELOCATING
        for k in due[np.sort(first)]:
            i = int(self._li[k])
            heard = table.indices[table.indptr[i]:table.indptr[i + 1]]
            if not (relocating[heard].any() or (started and np.isin(heard, started).any())):
                chosen.append(int(k))
                started.append(i)
        return np.array(chosen, dtype=np.int64)

    def waiting(self, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        """Which robots hear a relocating router on ``table``.

        While no move starts, a loss of theirs that falls due waits (:meth:`_choose`).
        """
        indptr = table.indptr
        rows = np.repeat(np.arange(len(indptr) - 1, dtype=np.int64), indptr[1:] - indptr[:-1])
        heard = np.zeros(len(indptr) - 1, dtype=bool)
        heard[rows[sw.state[table.indices] == State.RELOCATING]] = True
        return heard

    def _begin(self, chosen: np.ndarray, sw: Swarm) -> None:  # the way, not the loss, says where
        for i in self._li[chosen]:
            self.skips[i] = 0
            self._aim(int(i), sw.xy, fresh=True)

    def _aim(self, i: int, xy: np.ndarray, fresh: bool = False) -> bool:
        """Head router ``i`` for the first point of its way it has not reached; ``False``: none left.

        The go-to-goal state (progress, steps blocked) starts afresh only with a new point, or when ``fresh``.
        """
        node = start = self.node[i]
        while node >= 0 and np.hypot(*(xy[i] - self.crumbs.xy[node])) <= self.reach:
            node = self.crumbs.parent[node]
            self.skips[i] = 0
        if node < 0:
            return False
        self.node[i] = node
        if fresh or node != start:
            self.steering.start(np.array([i]), self.crumbs.xy[node][None], np.array([[-1]]))
        return True

    def steer(self, moving: np.ndarray, sw: Swarm, scans: np.ndarray, sensor_range: float,
              max_step: np.ndarray, r_keep: float) -> tuple[np.ndarray, np.ndarray]:
        """One step back along each router's way: ``(step_length, done)``; done: at its start or blocked too often."""
        end = np.zeros(len(moving), dtype=bool)
        for k, i in enumerate(moving):
            end[k] = not self._aim(int(i), sw.xy)
        length, blocked = self.steering.steer(moving, sw.xy, sw.heading, scans, sensor_range, max_step, r_keep)
        for k in np.flatnonzero(blocked & ~end):  # this point cannot be reached: skip it
            i = int(moving[k])
            self.skips[i] += 1
            self.skipped += 1
            self.node[i] = self.crumbs.parent[self.node[i]]
            end[k] = self.skips[i] >= MAX_SKIPS or not self._aim(i, sw.xy, fresh=True)
        length[end] = 0.0
        return length, end

    def steer_agents(self, t: float, contact: np.ndarray, sw: Swarm, scans: np.ndarray, sensor_range: float,
                     speed: np.ndarray, dt: float) -> np.ndarray:
        """Agents cut off for ``confirm_s`` back up their own path until they have a path again; their speeds.

        Args:
            t: Now, seconds.
            contact: Which agents have a path to a base station (their routing).
            sw: The robots (headings of backing agents set in place).
            scans: The agents' range readings.
            sensor_range: Their sensors' range.
            speed: The speeds the explorer gave them; a backing agent goes at its top speed.
            dt: Step length, seconds.
        """
        if not self.backing.any() and contact.all():  # (most steps: every agent in contact, none backs up)
            self.contact_at[:] = t
            return speed
        self.contact_at[contact] = t
        self.backing &= ~contact
        start = ~contact & ~self.backing & ~self.on_path & self.confirmed(t, self.contact_at)
        self.agent_backs += int(np.count_nonzero(start))
        self.backing |= start
        if not self.backing.any():
            return speed
        speed = speed.copy()
        for m in np.flatnonzero(self.backing):
            a = int(self.agents[m])
            node = self.crumbs.back(m, sw.xy[a], self.reach)
            if node < 0:  # at the start of its path and still cut off: it explores again
                self.backing[m] = False
                self.contact_at[m] = t
                continue
            if start[m] or self.steering.goal[a, 0] != self.crumbs.xy[node, 0] or \
                    self.steering.goal[a, 1] != self.crumbs.xy[node, 1]:
                self.steering.start(np.array([a]), self.crumbs.xy[node][None], np.array([[-1]]))
            step = np.array([sw.max_speed[a] * dt])
            length, blocked = self.steering.steer(np.array([a]), sw.xy, sw.heading, scans[m:m + 1], sensor_range, step,
                                                  np.inf)
            if blocked[0]:  # this point cannot be reached: skip it
                if len(self.crumbs.paths[m]) > 1:
                    self.crumbs.set_path(m, self.crumbs.paths[m][:-1])
                self.skipped += 1
            speed[m] = length[0] / dt
        return speed
