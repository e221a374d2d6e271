"""The drop rules' decisions as one compiled check: does any agent act this step, and if none, the rules' books kept.

Under every drop rule but the paper's alone (:attr:`~amronet.algorithms.agent_assisted.controller.AgentAssisted.
general_path`) the controller asks its rule at every step which agents drop a router and which are about to lose their
links (:meth:`~amronet.algorithms.agent_assisted.drops.DropRule.decide`, :meth:`~.DropRule.losing`), and, in most
steps, none is. :func:`rule_quiet` answers that question for the built-in rules with the same arithmetic on the same
numbers, so a compiled step (:mod:`amronet.algorithms.agent_assisted.fast`) knows whether the controller's own Python
must take over; in a quiet step :func:`rule_commit` keeps the rule's books as the rule would have kept them (the
link-quality rule's moving average, the distance-junction rule's path samples).

An agent *acts* when it drops a router (its rule says so, or it backs up under ``agents.reverse_drop`` and is in
contact again) or, tethered (``agents.when_empty: tether``), has no router left and is about to lose its links (it
turns back). The rules, by code:

* :data:`LOSING`: ``last-reference`` and ``strip-goals``, every reference heard at least ``r_eff`` away;
* :data:`RADIUS`: ``radius``, farther than ``R`` from every known relay, or its timer;
* :data:`JUNCTION`: ``distance-junction``, in contact and clear of the base, far from every relay, or at a junction
  or on a turn not near one;
* :data:`LINK`: ``link-quality``, the smoothed best margin below the drop threshold or the raw one below the loss
  threshold.

Every structure comes as a plain tuple in the order of its fields (see :mod:`.kernels`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.common.references import _best_margin as best_margins
from amronet.engine.hearing import open_margin
from amronet.engine.network import agents_linked_kernel

__all__ = ["JUNCTION", "LIMITS", "LINK", "LOSING", "PAPER", "RADIUS", "RuleBooks", "RuleInputs", "RuleStep",
           "agents_contact", "best_distance_margins", "junction_causes", "nearest_distances", "path_turning",
           "ring_openings", "rule_acts", "rule_commit", "rule_quiet", "same_network"]

PAPER = -1
"""No check: the paper's rule alone (an agent acts when the tracking finds it about to lose its last reference)."""
LOSING = 0
RADIUS = 1
JUNCTION = 2
LINK = 3

LIMITS = ("far", "every_s", "junction_clear", "turn_clear", "base_clear", "open_range", "cos_angle", "spacing",
          "drop_db", "loss_db", "alpha")
"""The rules' numbers in :attr:`RuleBooks.limits`, in this order (distances in metres; ``every_s`` nan: no timer)."""
_FAR, _EVERY, _JUNCTION, _TURN, _BASE, _OPEN, _COS, _SPACING, _DROP, _LOSS, _ALPHA = range(len(LIMITS))


class RuleBooks(NamedTuple):
    """The rule, its numbers and the books it keeps, per agent (``A``), as the controller and its rule hold them."""

    code: int
    """The rule (:data:`LOSING`, :data:`RADIUS`, :data:`JUNCTION`, :data:`LINK`)."""
    tether: bool
    """``agents.when_empty`` is ``tether``."""
    r_eff: float
    """The paper's "about to lose" distance."""
    limits: np.ndarray
    """The rule's numbers (:data:`LIMITS`)."""
    pending_until: np.ndarray
    """Until when each agent's last router settles ``(A,)``."""
    reversing: np.ndarray
    """Which agents back up (reverse drop) ``(A,)``."""
    last_drop: np.ndarray
    """``radius``: each agent's last drop, seconds ``(A,)``."""
    samples: np.ndarray
    """``distance-junction``: the path samples ``(A, 3, 2)``."""
    new_samples: np.ndarray
    """Scratch of the same shape: this step's samples, kept by :func:`rule_commit`."""
    smoothed: np.ndarray
    """``link-quality``: the moving average of each agent's best margin ``(A,)``."""
    new_smoothed: np.ndarray
    """Scratch ``(A,)``: this step's average, kept by :func:`rule_commit`."""


class RuleInputs(NamedTuple):
    """What the agents know this step."""

    t: float
    agents: np.ndarray
    xy: np.ndarray
    """Every robot's position ``(N, 2)``."""
    current: np.ndarray
    """Every robot's current reference ``(N,)`` (tracked this step)."""
    nearest_d: np.ndarray
    """Each agent's distance to its nearest reference heard ``(A,)``."""
    left: np.ndarray
    """Routers each robot carries ``(N,)``."""
    relay_xy: np.ndarray
    """The known relays ``(R, 2)``."""
    base_xy: np.ndarray
    """The base nodes ``(B, 2)``."""
    contact: np.ndarray
    """Whether each agent has a path to a base station ``(A,)`` (read by ``distance-junction`` and reverse drops)."""
    best: np.ndarray
    """``link-quality``: each agent's best margin to a reference ``(A,)``."""
    scans: np.ndarray
    """The agents' range readings ``(A, n_beams)``."""


class RuleStep(NamedTuple):
    """The rule's check in a quiet stretch (:func:`rule_acts`): its books and what stays fixed while nobody acts."""

    books: tuple
    """The rule's :class:`RuleBooks` (code :data:`PAPER`: none)."""
    relay_xy: np.ndarray
    """The known relays ``(R, 2)`` (no router settles in a stretch)."""
    base_xy: np.ndarray
    """The base nodes ``(B, 2)``."""
    bases: np.ndarray
    """Their indices."""
    relaying: np.ndarray
    """Which nodes relay ``(N,)`` (for the agents' contact)."""
    first: int
    """The stretch's first step (a step's time is its index times ``dt``, as the loop's clock)."""
    dt: float
    contact: np.ndarray
    """Scratch ``(A,)``: the agents' contact with a base station."""
    best: np.ndarray
    """Scratch ``(A,)``: the agents' best margins to a reference (read by the link-quality rule)."""


@njit(cache=True)
def _nearest(x, y, pts):  # pragma: no cover - numba
    """The distance from ``(x, y)`` to the nearest of ``pts``, as ``AgentView.nearest_relay_distance`` computes it."""
    best = np.inf
    for k in range(pts.shape[0]):
        dx = x - pts[k, 0]
        dy = y - pts[k, 1]
        d = math.sqrt(dx * dx + dy * dy)
        if d < best:
            best = d
    return best


@njit(cache=True)
def nearest_distances(xy, pts, out):  # pragma: no cover - numba
    """``out[m]``: the distance from ``xy[m]`` to the nearest of ``pts`` (:func:`_nearest`; none: ``inf``)."""
    for m in range(xy.shape[0]):
        out[m] = _nearest(xy[m, 0], xy[m, 1], pts)


@njit(cache=True)
def junction_causes(xy, relay_xy, base_xy, scans, allowed, turns, limits, out):  # pragma: no cover - numba
    """Why each agent drops under ``distance-junction``: ``out[m]`` 0 (it does not), 1 distance, 2 junction, 3 turn.

    What :meth:`~.drops.junction.DistanceJunction.decide` asks, agent by agent, as :func:`rule_quiet` does: ``xy``
    the agents' positions ``(A, 2)``, ``scans`` their rings, ``allowed`` the agents in contact that may drop ``(A,)``;
    ``turns`` = ``(samples, new, spacing, cos_angle)`` (:class:`~.drops.junction.PathTurns`, its samples kept in
    place); ``limits`` = ``(far, junction_clear, turn_clear, base_clear, open_range)`` in metres.
    """
    samples, new, spacing, cos_angle = turns
    far, junction_clear, turn_clear, base_clear, open_range = limits
    for m in range(xy.shape[0]):
        x = xy[m, 0]
        y = xy[m, 1]
        turning = path_turning(m, x, y, samples, new, spacing, cos_angle)
        near = _nearest(x, y, relay_xy)
        junction = ring_openings(scans[m], open_range) >= 3
        out[m] = 0
        if allowed[m] and _nearest(x, y, base_xy) > base_clear:
            if near > far:
                out[m] = 1
            elif junction and near > junction_clear:
                out[m] = 2
            elif turning and near > turn_clear:
                out[m] = 3
    for m in range(samples.shape[0]):  # (loops, not a slice copy: see rule_commit)
        for k in range(samples.shape[1]):
            for c in range(samples.shape[2]):
                samples[m, k, c] = new[m, k, c]


@njit(cache=True)
def ring_openings(scan, open_range):  # pragma: no cover - numba
    """Separate openings of one ring ``(n_beams,)``: circular runs of beams reading at least ``open_range``.

    A ring whose every beam is open (open floor) has one opening; one with none has zero.
    """
    nb = scan.shape[0]
    n = 0
    every = True
    for k in range(nb):
        here = scan[k] >= open_range
        if here and not scan[k - 1] >= open_range:  # (k - 1 = -1: the last beam, as numpy.roll)
            n += 1
        every = every and here
    return 1 if every else n


@njit(cache=True)
def path_turning(m, x, y, samples, new, spacing, cos_angle):  # pragma: no cover - numba
    """Agent ``m``'s samples after this step into ``new`` and whether it is on a turn.

    ``samples`` ``(A, 3, 2)``: each agent's oldest, middle and newest sample (nan: none yet). A new sample is taken
    where the agent at ``(x, y)`` is at least ``spacing`` from the newest; it is on a turn when the cosine of the
    angle between its two last directions is below ``cos_angle`` (no direction yet, a nan: no turn).
    """
    for j in range(3):
        new[m, j, 0] = samples[m, j, 0]
        new[m, j, 1] = samples[m, j, 1]
    if np.isnan(new[m, 2, 0]):
        new[m, 2, 0] = x
        new[m, 2, 1] = y
    dx = x - new[m, 2, 0]
    dy = y - new[m, 2, 1]
    if math.sqrt(dx * dx + dy * dy) >= spacing:
        for j in range(2):
            new[m, j, 0] = new[m, j + 1, 0]
            new[m, j, 1] = new[m, j + 1, 1]
        new[m, 2, 0] = x
        new[m, 2, 1] = y
    ux = new[m, 1, 0] - new[m, 0, 0]
    uy = new[m, 1, 1] - new[m, 0, 1]
    vx = new[m, 2, 0] - new[m, 1, 0]
    vy = new[m, 2, 1] - new[m, 1, 1]
    cos = (ux * vx + uy * vy) / (math.sqrt(ux * ux + uy * uy) * math.sqrt(vx * vx + vy * vy))
    if np.isnan(cos):
        cos = 1.0
    return cos < cos_angle


@njit(cache=True)
def rule_quiet(books, inputs):  # pragma: no cover - numba
    """Whether no agent acts this step (see the module docstring); the rule's books are left alone.

    Args:
        books: The rule and its books (:class:`RuleBooks`); this step's samples and average go to its scratch.
        inputs: What the agents know (:class:`RuleInputs`).
    """
    (code, tether, r_eff, limits, pending_until, reversing, last_drop, samples, new_samples, smoothed,
     new_smoothed) = books
    t, agents, xy, current, nearest_d, left, relay_xy, base_xy, contact, best, scans = inputs
    for m in range(agents.shape[0]):
        a = agents[m]
        x = xy[a, 0]
        y = xy[a, 1]
        can = left[a] >= 1 and pending_until[m] <= t
        if code == LOSING:
            losing = current[a] >= 0 and nearest_d[m] >= r_eff
            drop = losing and can
        elif code == RADIUS:
            losing = _nearest(x, y, relay_xy) > limits[_FAR]
            drop = (losing or (not np.isnan(limits[_EVERY]) and t - last_drop[m] >= limits[_EVERY])) and can
        elif code == JUNCTION:
            near = _nearest(x, y, relay_xy)
            turning = path_turning(m, x, y, samples, new_samples, limits[_SPACING], limits[_COS])
            losing = near > limits[_FAR]
            allowed = contact[m] and can and _nearest(x, y, base_xy) > limits[_BASE]
            junction = ring_openings(scans[m], limits[_OPEN]) >= 3
            drop = allowed and (losing or (junction and near > limits[_JUNCTION]) or (turning and near > limits[_TURN]))
        else:
            margin = best[m]
            old = smoothed[m]
            new = margin if np.isnan(old) else old + limits[_ALPHA] * (margin - old)
            if not np.isfinite(margin):
                new = np.nan
            new_smoothed[m] = new
            losing = (new < limits[_DROP] or margin < limits[_LOSS]) and np.isfinite(margin)
            drop = losing and can
        if drop or (reversing[m] and contact[m] and can) or (tether and losing and left[a] < 1):
            return False
    return True


@njit(cache=True)
def rule_commit(books):  # pragma: no cover - numba
    """Keep this step's books of a quiet step (what the rule's own ``decide`` and ``losing`` would have kept)."""
    code, _, _, _, _, _, _, samples, new_samples, smoothed, new_smoothed = books
    # loops, not slice copies: a slice copied from an array makes numba compile its shape-mismatch message (string
    # formatting, 1-2 s of `amronet compile` per rank of array and worker)
    if code == JUNCTION:
        for m in range(samples.shape[0]):
            for k in range(samples.shape[1]):
                for c in range(samples.shape[2]):
                    samples[m, k, c] = new_samples[m, k, c]
    elif code == LINK:
        for m in range(smoothed.shape[0]):
            smoothed[m] = new_smoothed[m]


@njit(cache=True, inline="always")
def same_network(bases, relaying, rule_bases, rule_relaying):  # pragma: no cover - numba
    """Whether the connection books and the drop rule ask for the agents' paths to the same bases and relays.

    Then the books' links at the end of a step (:func:`~.stretch_books.observe_links`) are the rule's contact at the
    next.
    """
    if bases.shape[0] != rule_bases.shape[0] or relaying.shape[0] != rule_relaying.shape[0]:
        return False
    for k in range(bases.shape[0]):
        if bases[k] != rule_bases[k]:
            return False
    for k in range(relaying.shape[0]):
        if relaying[k] != rule_relaying[k]:
            return False
    return True


@njit(cache=True, inline="always")
def agents_contact(after, needed, links, agents, rules, books):  # pragma: no cover - numba
    """The agents' contact with a base station at the start of a stretch's step, into the rule's ``contact`` scratch.

    ``after``: a step after the first, where the connection books' ``linked`` at the end of the step before
    (:func:`~.stretch_books.observe_links`) is that contact when both ask about the same network
    (:func:`same_network`): copied; else, where ``needed``, found on the table ``links`` = ``(indptr, indices)``.
    ``rules``: the drop rule's :class:`RuleStep`; ``books``: the connection books. Returns whether ``contact`` holds
    it.
    """
    _, _, _, bases, relaying, _, _, contact, _ = rules
    if after and same_network(books[0], books[1], bases, relaying):
        linked = books[2][0]
        for j in range(agents.shape[0]):
            contact[j] = linked[j]
        return True
    if needed:
        agents_linked_kernel(links[0], links[1], agents, bases, relaying, contact)
    return needed


@njit(cache=True)
def best_distance_margins(who, is_reference, indptr, indices, dist, r_c, n10, out):  # pragma: no cover - numba
    """``out[m]``: the best margin from ``who[m]`` to a reference it hears, its links' margins by their lengths.

    What :func:`~amronet.algorithms.common.references.best_reference_margin` reads of a table whose margins are
    :func:`~amronet.engine.links.distance_margins` (the unit disk, the path-loss law without walls and shadowing),
    each margin the same function of the same length, taken for the rows of ``who`` alone.
    """
    for m in range(who.shape[0]):
        i = who[m]
        best = -np.inf
        for e in range(indptr[i], indptr[i + 1]):
            if is_reference[indices[e]]:
                v = open_margin(dist[e], 0.0, 0.0, r_c, n10, 0.0, 0.0)
                if v > best:
                    best = v
        out[m] = best


@njit(cache=True)
def rule_acts(rules, done, agents, xy, current, nearest_d, left, scans, links, is_ref,
              known):  # pragma: no cover - numba
    """Whether an agent acts in step ``done`` of a stretch by the rule's check (:func:`rule_quiet`) on its table.

    ``rules``: a :class:`RuleStep`; the other arguments as :class:`RuleInputs` has them; ``links``: the table's
    ``(indptr, indices, dist, margin, law)``, ``law`` = ``(by_distance, r_c, n10)``: its margins (where the
    link-quality rule reads them) are those of its links' lengths, :func:`best_distance_margins`, else ``margin``;
    ``is_ref``: which nodes are references ``(N,)``; ``known``: the agents' contact with a base station on this
    table is in the :class:`RuleStep`'s ``contact`` already.
    """
    books, relay_xy, base_xy, bases, relaying, first, dt, contact, best = rules
    indptr, indices, dist, margin, law = links
    by_distance, r_c, n10 = law
    if books[0] == JUNCTION:
        if not known:
            agents_linked_kernel(indptr, indices, agents, bases, relaying, contact)
    elif books[0] == LINK:  # what best_reference_margin reads of the table
        if by_distance:
            best_distance_margins(agents, is_ref, indptr, indices, dist, r_c, n10, best)
        else:
            best_margins(agents, is_ref, indptr, indices, margin, best)
    t = (first + done) * dt
    return not rule_quiet(books, (t, agents, xy, current, nearest_d, left, relay_xy, base_xy, contact, best, scans))
