"""The inputs of an agent-assisted quiet stretch (:func:`~.stretch_kernels.quiet_stretch`), as named tuples.

:class:`~.stretch.QuietStretch` builds them from the controller's, the explorer's and the repair's state, and hands
them to the kernel as plain tuples (numba types a named tuple field by field at every call).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Frontier", "Moves", "Moving", "Triangles"]


class Moves(NamedTuple):
    """The agents and their moves."""

    agents: np.ndarray
    """The agents ``(A,)``."""
    length: np.ndarray
    """Each one's move per step ``(A,)``."""
    reach: float
    """The reach of the moves' collision checks."""
    collisions: bool
    """Whether bodies stop moves."""
    retracing: tuple
    """``repair: retrace``'s books of the agents (:class:`~.stretch_books.Retracing`, a plain tuple)."""
    reverse_drop: tuple
    """``agents.reverse_drop``'s books of the agents (:class:`~.stretch_books.ReverseDrop`, a plain tuple)."""
    until_linked: bool
    """Whether to stop after a step at whose end every agent has a path to a base station (a fault's damage may be
    repaired then)."""


class Triangles(NamedTuple):
    """The triangle rule's inputs (:func:`~.stretch_kernels.triangle_goes`)."""

    rule: int
    """A ``TRIANGLES_*`` code."""
    r_c: float
    """A candidate goes ahead when its references are farther apart than this."""
    disabled: np.ndarray
    """The nodes' local-rule flags ``(N,)``."""
    served: np.ndarray
    """The triangles served as rows ``(agent, lower reference, higher reference)``."""


class Moving(NamedTuple):
    """The triangle and strip routers driving to their goals, or the relocating routers, and how they steer.

    ``goal`` to ``min_progress`` as :class:`~amronet.algorithms.common.goto.GoalSteering` keeps them (triangle and
    strip routers steer with the controller's, relocating routers with the repair's).
    """

    tri: np.ndarray
    """The routers ``(T,)``: the triangle routers, then the strip routers, as the controller moves them; or the
    relocating routers (empty: none)."""
    angles: np.ndarray
    """Their ring's beam angles."""
    sensor_range: float
    """Their ring's range."""
    max_step: np.ndarray
    """Each one's longest step ``(T,)``."""
    goal: np.ndarray
    anchors: np.ndarray
    last_to_goal: np.ndarray
    blocked_steps: np.ndarray
    give_up: int
    min_progress: float
    r_keep: np.ndarray
    """A move may take each router no farther than this from an anchor (or than it is) ``(T,)``."""
    dt: float
    largest: float
    """The largest body radius."""
    refs: np.ndarray
    """``(N, n_anchors)``: the nodes each robot must hear where it settles (``GoalSteering.refs``)."""
    heard_xy: np.ndarray
    """``(N, 2)``: where each robot's table row last held one of them, kept in place (``GoalSteering.heard_xy``)."""
    tested: int
    """How many of the routers, the first (triangle routers), take the link test at settling: each step, one whose
    row of the table holds one of its ``refs`` is noted where it is (``GoalSteering.check_links``; 0: none, links
    decided by distance)."""
    network: np.ndarray
    """Relocating routers: the base nodes and routers ``(N,)``, whose links among them must stay ``links``
    (:func:`~.relocate_kernels.network_links`) for the repair to look at nothing new (empty: not watched)."""
    links: np.ndarray
    """Those links' keys (:func:`~.relocate_kernels.network_links`)."""


class Frontier(NamedTuple):
    """The frontier explorer's state and inputs for its navigation kernel, step after step.

    ``robots``, ``no_robots``, ``covered``, ``gap`` and ``visited`` are its layers, as in
    :class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.MapLayers`.
    """

    now: int
    """Its step count."""
    stamp: int
    """The knowledge grid's stamp."""
    avoid: float
    """Its avoidance reach."""
    bitgen: int
    """The run's generator's bit generator (:func:`amronet.engine.bitgen.addresses`): the fresh headings' uniforms,
    the idle agents' normals and uniforms are drawn from it in place, step by step, in the order the explorer draws."""
    sigma: float
    """The idle agents' heading noise per step, as
    :meth:`~amronet.algorithms.agent_assisted.explorers.random_walk.RandomExplorer.steer` scales it."""
    robots: np.ndarray
    no_robots: np.ndarray
    covered: np.ndarray
    gap: np.ndarray
    visited: np.ndarray
    settings: tuple
    """Its :class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.NavSettings` (a plain tuple)."""
    plans: tuple
    """Its :class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.AgentPlans` (a plain tuple)."""
    buffers: tuple
    """Its :class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.NavBuffers` (a plain tuple)."""
    active: np.ndarray
    """The plans' ``active``."""
