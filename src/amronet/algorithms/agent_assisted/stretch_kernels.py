"""The kernel of an agent-assisted run's quiet stretch: many whole steps in one compiled call.

A *quiet* step of an agent-assisted run with the frontier explorer is one in which no agent has to act (release a
router, turn back): the agents sense, track their references, put their readings into the shared grid, plan and
steer (an agent without a plan walks at random, drawing from the run's generator in place as numpy draws:
:func:`~amronet.engine.motion.random_walk_drawing`), and drive; the radio builds the next neighbour table; the
agents' connection is accounted. Most steps are quiet, and each is a dozen small calls with Python in between, most
of a step's time when there are a few agents. :func:`quiet_stretch` does up to ``limit`` such steps in a row, each
with the same compiled functions the step-by-step path calls, in the same order, on the same numbers, so the result
is the same bit for bit (:mod:`amronet.algorithms.agent_assisted.stretch` drives it; ``tests/test_agent_stretch.py``
compares).

A step in which an agent hears a reference of another network (a triangle candidate) is quiet too when no triangle
would go ahead by the local rule or none (:func:`~amronet.algorithms.common.triangular.select_triangles`): the
controller then does nothing but what a quiet step does. Under the global rule such a step ends the stretch. Triangle
routers driving to their goals, ``strip-goals``' routers driving to theirs (the same steering, another keep radius),
or routers relocating (``repair: relocate``, or ``retrace`` along their ways, the repair's steering), are steered
and moved with the agents, as the controller and the move phase do it, in the steps before one of them arrives or
gives up. Under ``retrace`` agents that back up their own path are steered as the repair steers them
(:mod:`~.retrace_kernels`). It stops at the first step that is not quiet, part-way through it, and says where: the
Python path finishes that step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.agent_assisted.explorers.frontier.navigation import navigate_kernel
from amronet.algorithms.agent_assisted.kernels import drive_movers, integrate_agents, sense_track_agents
from amronet.algorithms.agent_assisted.relocate_kernels import same_network_links
from amronet.algorithms.agent_assisted.retrace_kernels import aim_routers, retrace_stops, steer_backing
from amronet.algorithms.agent_assisted.rule_kernels import JUNCTION, LINK, PAPER, agents_contact, rule_acts, rule_commit
from amronet.algorithms.agent_assisted.stretch_books import Links, back_up, back_up_starts, observe_links
from amronet.algorithms.agent_assisted.stretch_links import Radio, margin_law, next_radio
from amronet.algorithms.common.goto import Steering, goal_ends, steer_one
from amronet.engine.bitgen import next_double
from amronet.engine.motion import random_walk_drawing
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = ["ACTS", "LINKED", "NON_FINITE", "QUIET", "TRIANGLES_ACT", "TRIANGLES_END", "TRIANGLES_LOCAL",
           "TRIANGLES_NONE", "TRIANGLE_RULES", "Links", "Radio", "StretchEnd", "quiet_stretch", "triangle_goes"]

QUIET = 0
"""Every step asked for was done."""
ACTS = 1
"""The step after the last one done: an agent must act. Sensed and tracked; nothing else done."""
NON_FINITE = 3
"""A robot's position became non-finite in the last step done (its radio table was not built)."""
LINKED = 5
"""Every agent had a path to a base station after the last step done (:attr:`~.stretch_tuples.Moves.until_linked`)."""

TRIANGLES_END = 4
"""The step after the last one done: a triangle or strip router driving to its goal arrives or gives up. Sensed,
tracked, in the grid, the agents steered; the routers' steering, the move and the radio are left."""

TRIANGLES_NONE = 0
"""Triangle rule ``none``: a candidate whose references are farther apart than ``r_c`` goes ahead."""
TRIANGLES_LOCAL = 1
"""Triangle rule ``local``: and its references are not both disabled."""
TRIANGLES_ACT = 2
"""Any other rule: a triangle candidate ends the stretch (the controller decides)."""
TRIANGLE_RULES = {"none": TRIANGLES_NONE, "local": TRIANGLES_LOCAL}
"""The triangle rules the kernel decides itself (``algorithm.params.triangular``), by name."""


class StretchEnd(NamedTuple):
    """What :func:`quiet_stretch` did."""

    steps: int
    """Steps done whole."""
    how: int
    """``QUIET``, ``ACTS``, ``TRIANGLES_END``, ``NON_FINITE`` or ``LINKED``."""
    n_cand: int
    """After ``ACTS`` or ``TRIANGLES_END``: that step's triangle candidates, as its tracking counts them."""
    n_losing: int
    """And its agents about to lose their last reference."""
    radio: tuple
    """The :class:`~.stretch_links.Radio` after the steps done (its tables, a plain tuple)."""
    scans: np.ndarray
    """After ``ACTS`` or ``TRIANGLES_END``: that step's agents' readings."""
    stamp: int
    """The knowledge grid's stamp."""
    explorer_steps: int
    """The explorer's step count."""
    looked: int
    """Steps with a triangle candidate and none going ahead."""
    idle: int
    """Steps done with an agent walking at random."""


@njit(cache=True)
def quiet_stretch(grid, robots, ring, moves, radio, tracking, who_acts, moving, knowledge, frontier, books,
                  limit):  # pragma: no cover - numba
    """Up to ``limit`` quiet steps; see the module docstring.

    Every argument but ``limit`` is a named structure, as a plain tuple: the map's
    :class:`~amronet.engine.kernel_data.Grid`; the robots (:class:`~amronet.algorithms.agent_assisted.kernels.Robots`,
    updated in place) and the agents' :class:`~amronet.algorithms.agent_assisted.kernels.Ring`; the agents' moves
    (:class:`~.stretch_tuples.Moves`); the :class:`~.stretch_links.Radio` (its tables built anew every step,
    :func:`~.stretch_links.next_radio`); the controller's
    :class:`~amronet.algorithms.agent_assisted.kernels.Tracking`; who acts, ``(triangles, rules)``: the
    :class:`~.stretch_tuples.Triangles` and the drop rule's
    :class:`~amronet.algorithms.agent_assisted.rule_kernels.RuleStep`; the triangle routers driving to
    their goals (:class:`~.stretch_tuples.Moving`); the frontier explorer's shared grid
    (:class:`~amronet.algorithms.agent_assisted.kernels.Knowledge`; the deployed nodes are fixed in a quiet stretch) and
    its state (:class:`~.stretch_tuples.Frontier`); the agents' connection books
    (:class:`~amronet.algorithms.stepping.AgentBooks`, its arrays a :class:`Links`,
    :meth:`amronet.sim.run.Run.connection_books`). ``limit``: the most steps to do. Under ``repair: retrace``
    (:attr:`~.stretch_tuples.Moves.retracing`) it may stop between two steps.

    Returns:
        A :class:`StretchEnd`.
    """
    xy, heading, radius, _, _ = robots
    angles, _ = ring
    agents, length, reach, collisions, retracing, reverse_drop, until_linked = moves
    current, is_ref, _, left, _, nearest_d, other_ref, refused = tracking
    triangles, rules = who_acts
    (tri, t_angles, t_sensor_range, max_step, goal, anchors, last_to_goal, blocked_steps, give_up, min_progress,
     r_keep, dt, largest, refs, heard_xy, tested, network, links) = moving
    cells, _, _, _, _ = knowledge
    score, seen, _, _, _, row_stamp = cells
    (now, stamp, avoid, bitgen, sigma, layer_robots, no_robots, covered, gap, visited, settings, plans, buffers,
     active) = frontier
    blocked, clear, ox, oy, res = grid
    trail = retracing[0]
    backs = trail.shape[0] > 0 and retracing[6].any()  # (retrace's agents backing up)
    _, _, _, _, _, rule_first, rule_dt, rule_contact, _ = rules
    linked = books[2][0]
    m = agents.shape[0]
    n = xy.shape[0]
    nt = tri.shape[0]
    retraced = tri[:nt if network.shape[0] else 0]  # (under retrace: the routers retracing their way)
    movers = np.empty(m + nt, np.int64)  # the agents, then the triangle routers (the controller's order)
    lengths = np.empty(m + nt)
    for j in range(m):
        movers[j] = agents[j]
        lengths[j] = length[j]
    for q in range(nt):
        movers[m + q] = tri[q]
    t_scans = np.empty((nt, t_angles.shape[0]))
    group = np.zeros(n, np.int64)
    refused_m = np.empty(m, np.bool_)
    fresh = np.empty(m)
    normal = np.empty(m)  # (the idle agents' draws)
    uniform = np.empty(m)
    no_bodies = (np.zeros(n + 1, np.int64), np.zeros(0, np.int32), np.zeros(0))
    paper = rules[0][0] == PAPER
    backing = reverse_drop[0].shape[0] > 0  # (agents.reverse_drop)
    margins, law = margin_law(rules[0][0] == LINK, radio[10])  # (whether the tables keep the margins the rule reads)
    contact = rules[0][0] == JUNCTION or backing  # (the rule or the reverse drop reads the agents' contact)
    done = np.int64(0)  # (typed so from the start: a callee is compiled for it once)
    looked = 0
    idle = 0
    while done < limit:
        if done and network.shape[0] and not same_network_links(radio[1], radio[2], network, links):  # (relocate)
            return StretchEnd(done, QUIET, 0, 0, radio, np.empty((m, angles.shape[0])), stamp, now, looked, idle)
        if trail.shape[0]:  # retrace: the contact, a step its own code must take (retrace_stops); the odometry
            if retrace_stops(retracing, done, agents, xy, linked, retraced):
                return StretchEnd(done, QUIET, 0, 0, radio, np.empty((m, angles.shape[0])), stamp, now, looked,
                                  idle)
            for j in range(m):
                trail[done, j, 0] = xy[agents[j], 0]
                trail[done, j, 1] = xy[agents[j], 1]
        _, indptr, indices, dist, margin, near_indptr, near_indices, near_dist, _, _, _, _ = radio
        scans = np.empty((m, angles.shape[0]))
        near = (near_indptr, near_indices, near_dist)  # the rings and the moves read every pair within r
        known = agents_contact(contact and done > 0, backing, (indptr, indices), agents, rules, books)
        if backing and back_up_starts(reverse_drop, (rule_first + done) * rule_dt, agents, left, rule_contact):
            # (reverse drop: stop before a step in which an agent starts to back up)
            return StretchEnd(done, QUIET, 0, 0, radio, np.empty((m, angles.shape[0])), stamp, now, looked, idle)
        n_cand, n_losing = sense_track_agents(grid, robots, agents, ring, near, scans, tracking,
                                              (indptr, indices, dist), paper, knowledge, stamp + 1)
        if not paper:  # the drop rule decides who acts
            if ((n_cand and triangle_goes(triangles, agents, current, other_ref, left, xy))
                    or rule_acts(rules, np.int64(done), agents, xy, current, nearest_d, left, scans,  # (no literal 0)
                                 (indptr, indices, dist, margin, law), is_ref, known)):
                return StretchEnd(done, ACTS, n_cand, n_losing, radio, scans, stamp, now, looked, idle)
            rule_commit(rules[0])
            looked += 1 if n_cand else 0
            integrate_agents(robots, agents, ring, scans, knowledge, stamp + 1)
        elif n_cand and not n_losing and not triangle_goes(triangles, agents, current, other_ref, left, xy):
            # the controller would only look: the rest of sense_track_agents, as in a quiet step
            looked += 1
            integrate_agents(robots, agents, ring, scans, knowledge, stamp + 1)
        elif n_cand or n_losing:
            return StretchEnd(done, ACTS, n_cand, n_losing, radio, scans, stamp, now, looked, idle)
        stamp += 1
        # the frontier explorer's plan_and_steer: its uniforms (rng.uniform(-pi, pi, m) as it scales them), ...
        for j in range(m):
            fresh[j] = -np.pi + (2.0 * np.pi) * next_double(bitgen)
            refused_m[j] = refused[agents[j]]
        avoided = np.empty((m, angles.shape[0]))
        for j in range(m):
            for k in range(angles.shape[0]):
                avoided[j, k] = min(scans[j, k], avoid)
        navigate_kernel((now, np.bool_(False), xy, heading, agents, avoided, angles, refused_m, fresh),
                        (score, seen, row_stamp, stamp, layer_robots, no_robots, covered, gap, visited), settings,
                        plans, buffers)
        now += 1
        # ... then the agents its plans left idle walk at random (steer_idle; a plan may come back any step)
        walked = random_walk_drawing(bitgen, heading, agents, active, avoided, angles, avoid, refused_m, sigma, normal,
                                     uniform)
        if backing:  # the reverse drop's books, and the agents that back up (their contact as above)
            back_up(reverse_drop, (rule_first + done) * rule_dt, agents, xy, heading, rule_contact)
        reach_now = reach
        if retraced.shape[0] and trail.shape[0]:  # retrace's routers take the points they have reached
            aim_routers(retracing, retraced, xy)
        for q in range(nt):  # a triangle, strip or relocating router that arrives or gives up now ends the stretch
            if goal_ends(tri[q], xy, Steering(goal, anchors, last_to_goal, blocked_steps, give_up, min_progress),
                         max_step[q]):
                return StretchEnd(done, TRIANGLES_END, 0, 0, radio, scans, stamp, now, looked, idle)
        if backs:  # retrace's backing agents, as the repair steers them once the explorer has
            reach_now = 2.0 * largest + 2.0 * steer_backing(retracing, agents, xy, heading, scans, angles, lengths, dt)
        if nt:  # the routers' rings, then their steering
            for q in range(nt):
                i = tri[q]
                cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], t_angles, t_sensor_range,
                              t_scans[q])
                if n > 1:
                    cast_bodies_one(i, near_indptr, near_indices, near_dist, xy, heading[i], t_angles, t_sensor_range,
                                    radius, largest, t_scans[q])
            farthest = 0.0
            for j in range(m):
                farthest = max(farthest, lengths[j])
            for q in range(nt):
                step, _ = steer_one(tri[q], xy, heading,
                                    Steering(goal, anchors, last_to_goal, blocked_steps, give_up, min_progress),
                                    t_scans[q], t_angles, t_sensor_range, max_step[q], r_keep[q])
                lengths[m + q] = (step / dt) * dt  # the command's speed times the step, as the move phase has it
                farthest = max(farthest, lengths[m + q])
            for q in range(tested):  # the link test's note of where each hears one of its references (this table)
                i = tri[q]
                for k in range(refs.shape[1]):
                    if refs[i, k] >= 0 and _in_row(indptr, indices, i, refs[i, k]):
                        heard_xy[i, 0] = xy[i, 0]
                        heard_xy[i, 1] = xy[i, 1]
                        break
            reach_now = 2.0 * largest + 2.0 * farthest  # the move phase's reach, over every mover
        # the move, then the radio's next table and the agents' connection
        drive_movers(grid, robots, movers, lengths, collisions, near if collisions else no_bodies, reach_now, refused)
        ok, radio = next_radio(xy, radio, group, margins)
        done += 1
        idle += 1 if walked else 0
        if not ok:
            return StretchEnd(done, NON_FINITE, 0, 0, radio, scans, stamp, now, looked, idle)
        if observe_links(radio[1], radio[2], agents, books) and until_linked:  # (the links)
            return StretchEnd(done, LINKED, 0, 0, radio, scans, stamp, now, looked, idle)
    return StretchEnd(done, QUIET, 0, 0, radio, np.empty((m, angles.shape[0])), stamp, now, looked, idle)


@njit(cache=True, inline="always")
def _in_row(indptr, indices, i, a):  # pragma: no cover - numba
    """Whether node ``a`` is in row ``i`` of a table (its links: every margin finite, distances being clamped)."""
    for p in range(indptr[i], indptr[i + 1]):
        if indices[p] == a:
            return True
    return False


@njit(cache=True)
def triangle_goes(triangles, agents, current, other, left, xy):  # pragma: no cover - numba
    """Would a triangle go ahead this step? What ``AgentAssisted.decide_tracked`` asks ``select_triangles``.

    The candidates are the agents that hear a reference of another status (``other[m]``) and carry a router, less
    the triangles they served already; one goes ahead when its references are farther apart than ``r_c`` (the
    distance as ``numpy.linalg.norm`` computes it) and, by the local rule, not both disabled
    (:class:`~.stretch_tuples.Triangles`).
    """
    rule, r_c, disabled, served = triangles
    if rule == TRIANGLES_ACT:
        return True
    for m in range(agents.shape[0]):
        a = agents[m]
        o = other[m]
        if o < 0 or left[a] < 1:
            continue
        cur = current[a]
        lo = min(cur, o)
        hi = max(cur, o)
        fresh = True
        for k in range(served.shape[0]):
            if served[k, 0] == a and served[k, 1] == lo and served[k, 2] == hi:
                fresh = False
                break
        if not fresh:
            continue
        dx = xy[cur, 0] - xy[o, 0]
        dy = xy[cur, 1] - xy[o, 1]
        if math.sqrt(dx * dx + dy * dy) > r_c and (rule == TRIANGLES_NONE or not (disabled[cur] and disabled[o])):
            return True
    return False
