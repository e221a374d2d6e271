"""The repair's part of the compiled step and of quiet stretches (``repair: relocate`` and ``retrace``).

Every step the controller's :meth:`~.movers.Movers.movers_command` lets the repair look (:meth:`.Relocator.update`):
it compares the links among the *watched* nodes (base nodes, deployed and relocating routers) with the last ones,
starts the moves of cut-off routers whose losses are due and stops those that have a path again. Under ``retrace``
the agents' odometry is recorded, and agents out of contact for ``repair_confirm_s`` back up
(:meth:`.Retracer.steer_agents`). :class:`RepairStep` does this part of a step where the compiled step
(:class:`~.fast.CompiledAgents`) and its quiet stretches (:class:`~.stretch.QuietStretch`) take the rest:

* A compiled step in which routers relocate or agents back up goes phase by phase (:meth:`RepairStep.busy`), but
  the relocating routers are steered in stretches while the repair's look changes nothing
  (:meth:`RepairStep.relocating_start`): this step's look is taken at the start, the stretch ends before a loss of
  a cut-off router falls due (under ``retrace``: of one that would not wait for a neighbour), and its kernel stops
  before a step whose table has other links among the base nodes and routers than this one (a loss noticed or heard
  again, a router that finds a path). Under ``retrace`` the kernel takes the next points of the routers' ways and of
  the backing agents' paths, and steers the backing agents (:mod:`~.retrace_kernels`).
* The relocator is *idle* when nobody relocates, no loss waits whose router may move and is cut off, and the links
  among the watched nodes are those it last saw. Deployed nodes do not move, so under a radio whose links are decided
  by the positions (:attr:`~amronet.algorithms.stepping.StepContext.link_inputs`: the unit disk, the built-in
  path-loss law without packet loss) it stays idle until a node is added, changes state (the controller's
  ``_nodes_changed``) or fails; meanwhile its ``update`` would change nothing but its caches of the last table,
  which are kept by value (the same links give the same answers), so it is not called (:meth:`RepairStep.quiet`).
* ``retrace``'s agents are steered as the controller does it, in its own code, every compiled step; in a stretch the
  kernel notes their contact and stops before one of them would start or stop backing up, and the odometry of those
  that do not is replayed from the positions it hands back (:class:`~.stretch_books.Retracing`).

Every other step of the controller's (an agent acts, triangle or strip routers drive) runs the controller's own
``movers_command``, repair included.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from amronet.algorithms.agent_assisted.relocate import Relocator
from amronet.algorithms.agent_assisted.relocate_kernels import network_links
from amronet.algorithms.agent_assisted.retrace import Retracer
from amronet.algorithms.agent_assisted.stretch_books import Retracing, no_retracing
from amronet.algorithms.base import StepInput
from amronet.algorithms.common.goto import GoalSteering, steering_of
from amronet.algorithms.stepping import StepContext
from amronet.engine.network import agents_connected, connected_to
from amronet.engine.robots import Role, State

__all__ = ["RelocatingWatch", "RepairStep"]


class RelocatingWatch(NamedTuple):
    """What a stretch that steers relocating routers needs of the repair (:meth:`RepairStep.relocating_start`)."""

    routers: np.ndarray
    """The relocating routers."""
    steering: GoalSteering
    """Their steering, the repair's."""
    network: np.ndarray
    """The base nodes and routers (a mask over the robots)."""
    links: np.ndarray
    """The links among them on the table the stretch starts from (:func:`~.relocate_kernels.network_links`)."""


class RepairStep:
    """The repair's part of a compiled agent-assisted step (see the module docstring).

    Args:
        controller: The loop's controller (with a relocator).
        context: The loop's step context.
    """

    def __init__(self, controller: Any, context: StepContext) -> None:
        self.controller = controller
        self.relocator = controller.relocator
        self.retracer: Retracer | None = self.relocator if isinstance(self.relocator, Retracer) else None
        self.fixed_links = context.link_inputs is not None
        """Whether the links among nodes that stand still stay as they are (no packet loss)."""
        self._idle: tuple | None = None
        """What the relocator was found idle with: the controller's deployed mask, the robots, the failed nodes."""
        self.updates_skipped = 0
        """Compiled steps in which the idle relocator's ``update`` was not called."""
        self.watch: RelocatingWatch | None = None
        """In a stretch that steers relocating routers: what it watches; else ``None``."""
        self.relocating_steps = 0
        """Steps taken in stretches with routers relocating."""
        self.backing_steps = 0
        """Steps taken in stretches with agents backing up (``retrace``)."""
        self._backing = False
        """Whether agents back up in the stretch under way."""

    def busy(self) -> bool:
        """Whether routers relocate or agents back up: a compiled step goes phase by phase (a stretch steers them)."""
        if (self.controller.swarm.state == State.RELOCATING).any():
            return True
        return self.retracer is not None and bool(self.retracer.backing.any())

    def _token(self) -> tuple:
        c = self.controller
        sw = c.swarm
        return c.deployed_nodes()[0], len(sw), int(np.count_nonzero(sw.state == State.FAILED))

    def idle(self) -> bool:
        """Whether the relocator was found idle and nothing it watches has changed since (the module docstring)."""
        kept = self._idle
        if kept is None:
            return False
        now = self._token()
        return now[0] is kept[0] and now[1:] == kept[1:]

    def _note_idle(self, table: Any) -> None:
        """After the relocator's ``update``: keep what it is idle with, or forget it.

        Only where ``table`` has every robot (a router put down since it was built has no links in it yet).
        """
        r, sw = self.relocator, self.controller.swarm
        idle = self.fixed_links and len(table.indptr) - 1 == len(sw) and not (sw.state == State.RELOCATING).any()
        if idle:
            idle = not r.may_start(table, sw)
        self._idle = self._token() if idle else None

    def quiet(self, now: StepInput, scans: np.ndarray) -> np.ndarray:
        """The end of ``movers_command`` in a step in which only the agents move; their speeds.

        ``retrace``'s agents are steered (:meth:`.Retracer.steer_agents`); the relocator looks, unless it is idle
        (then only the odometry is recorded).
        """
        c, r = self.controller, self.relocator
        sw = c.swarm
        speed = c.explorer.speed(c.agent_speed)
        if self.retracer is not None:
            contact = agents_connected(now.table, c.agents, c.bases, sw.relaying)
            speed = self.retracer.steer_agents(now.t, contact, sw, scans, sw.models[c.agent_model].sensor_range,
                                               speed, c.dt)
        if self.idle():
            r.odometry(sw)
            self.updates_skipped += 1
            return speed
        started, stopped = r.update(now.t, now.table, sw)
        if len(started) or len(stopped):  # (as movers_command: those that start move from the next step)
            sw.state[started] = State.RELOCATING
            sw.state[stopped] = State.REFERENCE
            c._nodes_changed()
        self._note_idle(now.table)
        return speed

    def stretch_start(self, now: StepInput, limit: int) -> tuple[Retracing, int] | None:
        """What a stretch keeps of the repair from this step on (:class:`~.stretch_books.Retracing`); its most steps.

        ``None``: no stretch now (the relocator is not idle, not even after its look taken here (:meth:`_look`), or
        routers drive that ``retrace`` would record, or a relocating router's loss might start; an agent starts or
        stops backing up now, or one is back at the start of its path; routers relocate that
        :meth:`relocating_start` does not let move in it). Under ``retrace`` this step's contact is noted, and the
        backing agents head for their points, as :meth:`.Retracer.steer_agents` does first.
        """
        c, r = self.controller, self.relocator
        sw = c.swarm
        self.watch = None
        b = self.retracer
        if b is not None:
            contact = agents_connected(now.table, c.agents, c.bases, sw.relaying)
            at = np.where(contact, now.t, b.contact_at)
            if (~contact & ~b.backing & ~b.on_path & b.confirmed(now.t, at)).any() or (contact & b.backing).any():
                return None
        if (sw.state == State.RELOCATING).any():
            limit = self.relocating_start(now, limit)
            if not limit:
                return None
        else:
            driving = c.moving_triangles or (c.strips is not None and c.strips.moving)
            if not self.idle() and (driving or not self._look(now)):
                return None
            if driving and (b is not None or r.waiting_movable(sw).any()):
                return None  # (triangle or strip routers on their way add to their way, or may cut a router off)
        m = len(c.agents)
        if b is None:
            return no_retracing(m), limit
        b.contact_at[:] = at
        self._backing = bool(b.backing.any())
        crumbs = b.crumbs
        return Retracing(np.empty((limit, m, 2)), b.contact_at, b.on_path, float(b.confirm_s), int(now.index),
                         float(now.dt), b.backing, float(b.reach), float(sw.models[c.agent_model].sensor_range),
                         sw.max_speed[c.agents] * c.dt, tuple(steering_of(b.steering)), crumbs.xy, crumbs.parent,
                         crumbs.path_rows, crumbs.length, crumbs.tip, b.node, b.skips), limit

    def relocating_start(self, now: StepInput, limit: int) -> int:
        """Routers relocating in a stretch: this step's look, taken here; how many steps (0: none).

        Only where :meth:`_look` may look (links decided by the positions, no reverse drops, the table has every
        robot), no triangle or strip router drives, and the look starts and stops nothing: no relocating router has a
        path to a base station and no move could start now. In the stretch's later steps the look would change
        nothing as long as the links among the base nodes and routers are this table's (:attr:`watch`: the kernel
        stops before a step whose table has others) and no loss of a cut-off router that may move falls due
        (:meth:`.Relocator.quiet_steps`: the stretch ends before; under ``retrace`` a router that hears a relocating
        one waits all through the stretch, :meth:`.Retracer.waiting`). A router that finds a path again does so in
        the stretch's last step, which the faults' books see. The look records no odometry: the stretch records its
        first step's.
        """
        c, r, table = self.controller, self.relocator, now.table
        sw = c.swarm
        if (not self.fixed_links or c.trails is not None or len(table.indptr) - 1 != len(sw) or r.confirm_s <= 1e-9
                or c.moving_triangles or (c.strips is not None and c.strips.moving)
                or (sw.state == State.TRIANGLE).any() or (sw.state == State.STRIP).any()):
            return 0
        network = sw.role != Role.AGENT
        cut = ~connected_to(table, np.flatnonzero(sw.role == Role.BASE), network)
        moving = np.flatnonzero(sw.state == State.RELOCATING)
        if not cut[moving].all() or r.could_start(now.t, table, sw, cut):
            return 0
        started, stopped = Relocator.update(r, now.t, table, sw)  # (retrace: the stretch records the odometry)
        assert not len(started) and not len(stopped), "a look at the start of a stretch moved a router"
        self._note_idle(table)
        self.watch = RelocatingWatch(moving, r.steering, network, network_links(table.indptr, table.indices, network))
        if self.retracer is not None:  # (routers that wait for one relocating wait all through the stretch)
            cut = cut & ~self.retracer.waiting(table, sw)
        return r.quiet_steps(int(now.index), float(now.dt), limit, cut, sw)

    def _look(self, now: StepInput) -> bool:
        """The relocator's look of this step (its ``update``), taken at the start of a stretch; whether it is idle then.

        Only where the look can start and stop nothing (nobody relocates or drives, no move can start now
        (:meth:`.Relocator.could_start`), and a loss it notices now is not due before ``confirm_s``), and no router can
        be picked up in the step (no reverse drops), so that it leaves what the step's own look would: the same call on
        the same table, and a second call in the step (an agent acts in it) adds at most the links of a router put
        down. Under ``retrace`` the odometry is not recorded here: the stretch records its first step's (or the step's
        own look, where an agent acts in it, after the agent has put its router down and extended its way).
        """
        c, r, table = self.controller, self.relocator, now.table
        sw = c.swarm
        if (not self.fixed_links or c.trails is not None or len(table.indptr) - 1 != len(sw) or r.confirm_s <= 1e-9
                or r.could_start(now.t, table, sw)
                or (sw.state == State.TRIANGLE).any() or (sw.state == State.STRIP).any()):
            return False
        started, stopped = Relocator.update(r, now.t, table, sw)  # (without Retracer.update's odometry)
        assert not len(started) and not len(stopped), "a look at the start of a stretch moved a router"
        self._note_idle(table)
        return self.idle()

    def stretch_end(self, done: int, retracing: Retracing) -> None:
        """After a stretch of ``done`` whole steps: ``retrace``'s odometry of them (the kernel noted the contact)."""
        self.updates_skipped += done
        if self.watch is not None:
            self.relocating_steps += done
            self.watch = None
        if self._backing:
            self.backing_steps += done
            self._backing = False
        if self.retracer is not None and done:
            self.retracer.crumbs.replay(retracing.trail[:done], ~retracing.backing)
