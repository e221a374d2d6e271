"""Random exploration: the paper's ``"random"`` explorer, and ``"random-escape"``, a random walk that leaves rooms.

``"random"`` (the paper's, unchanged): keep the heading up to Gaussian noise (``turn_noise``, 0.5 rad per
square-root second); when a forward beam (less than 90 degrees off the heading) reads less than ``avoid_range``
(0.6 m), turn to the escape heading of :func:`~amronet.engine.motion.avoidance_heading`, away from everything within
``avoid_range`` weighted by closeness; after a refused move, a uniform heading.

Why it stays in rooms: to it a doorway narrower than about ``2 x avoid_range`` (1.2 m; office doors are
1.0-1.2 m) is nearly a wall. Going through, each jamb passes beside the agent at no more than the door's half-width
(0.5 m for a 1.0 m door), and while a jamb is between 56 and 90 degrees off the heading the beam at 67.5 degrees of
the 16-beam ring reads it at about ``half-width / sin 67.5°`` (0.54 m), inside ``avoid_range``, whatever the
agent's line or heading. The escape heading, pushed by both jambs, replaces the heading (the noise cannot undo it)
and points back into the room: an agent driving straight at a 1.0 m door, centred and without noise, turns round
0.2 m before it. One that comes in at a slant rattles between the jambs, each bounce moving it a few centimetres
forward or back at random, and gets out only when those add up to the wall's thickness. With ``avoid_range`` below
the half-width (0.4 m for a 1.0 m door) a centred agent passes.

``"random-escape"`` keeps the random walk — straight runs with the same heading noise, random turns — and changes
what makes an agent turn and where it turns to. It uses the agent's own sonar and its own odometry (a memory of
how long it spent around each 0.5 m cell of the area's bounding box; a step counts for the 3 x 3 cells around it):

* **In the way, not merely near**: a direction is *open* when no reading lies in the corridor a body would sweep
  along it for ``reach`` metres (:func:`open_directions`; ``reach`` = the smaller of ``avoid_range`` and the sonar
  range, half-width ``WIDTH_FRACTION x reach``: 0.6 m and 0.25 m for the Pioneer, whose radius is 0.22 m). The
  agent turns only when straight ahead is not open or its last move was refused. Jambs beside its line do not
  turn it back.
* **Random reflection, toward the less visited**: it then turns to an open beam direction drawn with the run's
  generator, each weighing ``exp(-(s - s_min) / NOVELTY_S)``, where ``s`` is the time it spent around where that
  direction leads (the point ``LOOK_FRACTION`` of the sonar range along a beam that sees nothing; for a beam that
  sees something, where it stands) and ``s_min`` the least over the open directions.
* **Lured by new places**: when some open beam sees nothing and leads to a place the agent has spent less than
  ``NEW_S`` around, and straight ahead does not, it turns to one of those drawn at random (then not again for
  ``COMMIT_S``). A doorway into a corridor it has not been in is such a place.
* With no open direction at all it turns to the paper's escape heading (or round).

Each step an agent draws one normal number (its heading noise) and one uniform number (which direction, when it
turns). ``benchmarks/bench_escape.py`` measures how long agents of both explorers take to leave a room.

Not undone here: a router put down in the middle of a 1.0 m doorway (an agent releases it next to itself, toward its
reference) leaves two 0.455 m gaps, too narrow for a Pioneer (0.44 m) to find; agents still in the room stay there.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS, Explorer
from amronet.engine.motion import avoidance_heading, random_walk
from amronet.engine.sensing import beam_angles
from amronet.engine.streams import draw_per_run

__all__ = ["RandomEscapeExplorer", "RandomExplorer", "open_directions"]

WIDTH_FRACTION = 0.42
"""Half-width of the corridor checked ahead, as a fraction of the reach (0.25 m for a 0.6 m ``avoid_range``)."""
MEMORY_CELL_M = 0.5
"""Cell size of an agent's memory of where it has been, metres; a step counts for the 3 x 3 cells around it."""
LOOK_FRACTION = 0.75
"""Where a direction leads: the point this fraction of the sonar range along it (1.5 m for the Pioneer)."""
NEW_S = 1.0
"""A place is new while the agent has spent less than this many seconds around it."""
COMMIT_S = 1.5
"""After turning toward a new place, the agent is not lured again for this many seconds."""
NOVELTY_S = 2.0
"""Turning away from an obstacle, an open direction weighs ``exp(-(seconds spent where it leads, more than the
least visited open direction) / NOVELTY_S)``."""


@EXPLORERS.register("random")
class RandomExplorer(Explorer):
    """Random exploration with sonar-based obstacle avoidance (the paper's agents).

    Agents keep their heading up to Gaussian noise; when a forward sonar reads less than ``avoid_range`` they
    turn away from what they see; after a refused move they pick a uniform random heading.
    """

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        reach = min(sensor_range, self.avoid_range)
        random_walk(heading, who, np.minimum(scans, reach), reach, refused, rng, self.turn_noise * np.sqrt(self.dt))


def open_directions(scans: np.ndarray, sensor_range: float, reach: float, half_width: float) -> np.ndarray:
    """Which beam directions have a clear corridor ahead: nothing read in the rectangle a body would sweep.

    A reading ``d`` of beam ``k`` (``d < sensor_range``: the beam saw something) blocks direction ``j`` when, seen
    from direction ``j``, its point lies ahead by less than ``reach`` and beside the line by less than
    ``half_width``.

    Args:
        scans: Sonar ranges ``(A, n_beams)``, beam 0 along the heading, beams evenly spaced counter-clockwise.
        sensor_range: Maximum range: a reading this long saw nothing.
        reach: Length of the corridor, metres.
        half_width: Half its width, metres.

    Returns:
        ``(A, n_beams)``: ``True`` where the corridor along beam ``j`` is clear (column 0: straight ahead).
    """
    n = scans.shape[1]
    angles = beam_angles(n)
    rel = angles[None, :] - angles[:, None]  # rel[j, k]: beam k's angle seen from direction j
    cos, sin = np.cos(rel), np.sin(rel)
    seen = scans < sensor_range
    along = scans[:, None, :] * cos[None]
    beside = np.abs(scans[:, None, :] * sin[None])
    in_way = seen[:, None, :] & (cos[None] > 1e-9) & (along < reach) & (beside < half_width)
    return ~in_way.any(axis=2)


def _escape_draws(rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray]:
    """``m`` standard normal (heading noise), then ``m`` standard uniform numbers (which direction, when turning)."""
    return rng.standard_normal(m), rng.random(m)


def _pick(weight: np.ndarray, uniform: np.ndarray) -> np.ndarray:
    """Column drawn in each row with probability proportional to ``weight`` (rows with positive sum)."""
    cum = np.cumsum(weight, axis=1)
    return np.minimum((cum <= (uniform * cum[:, -1])[:, None]).sum(axis=1), weight.shape[1] - 1)


@EXPLORERS.register("random-escape")
class RandomEscapeExplorer(Explorer):
    """A random walk that leaves rooms (see the module docstring).

    Each step every agent draws one normal number (its heading noise, ``turn_noise`` per square-root second as
    the paper's) and one uniform number (which direction it turns to, when it turns). Each agent remembers how
    long it spent around every cell of a ``MEMORY_CELL_M`` grid over the area's bounding box (its own odometry).
    """

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float]) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        xmin, xmax, ymin, ymax = extent
        self._shape = (max(1, int(np.ceil((ymax - ymin) / MEMORY_CELL_M))),
                       max(1, int(np.ceil((xmax - xmin) / MEMORY_CELL_M))))
        self._ids = np.zeros(0, dtype=np.int64)
        """The robots the memory rows belong to (the agents of the last step)."""
        self._visits = np.zeros((0, *self._shape))
        """Seconds each agent spent around each memory cell ``(A, rows, cols)``."""
        self._quiet = np.zeros(0)
        """Seconds until each agent may be lured again."""

    def _follow(self, who: np.ndarray) -> None:
        """Line the memory rows up with ``who``: an agent keeps its memory when the set of agents steered changes.

        With ``agents.trajectories`` this explorer steers the agents whose paths have ended, more and more of them.
        """
        if np.array_equal(who, self._ids):
            return
        visits, quiet = np.zeros((len(who), *self._shape)), np.zeros(len(who))
        known = np.isin(who, self._ids)
        if known.any():
            row_of = {int(i): k for k, i in enumerate(self._ids)}  # a handful of agents, once per change
            rows = np.array([row_of[int(i)] for i in who[known]])
            visits[known], quiet[known] = self._visits[rows], self._quiet[rows]
        self._ids, self._visits, self._quiet = who.copy(), visits, quiet

    def _cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Memory cells ``(rows, cols)`` of points ``(..., 2)``, clipped to the grid."""
        xmin, _, ymin, _ = self.extent
        rows = np.clip(np.floor((points[..., 1] - ymin) / MEMORY_CELL_M).astype(np.int64), 0, self._shape[0] - 1)
        cols = np.clip(np.floor((points[..., 0] - xmin) / MEMORY_CELL_M).astype(np.int64), 0, self._shape[1] - 1)
        return rows, cols

    def _remember(self, rows: np.ndarray, cols: np.ndarray) -> None:
        """Add a step to the 3 x 3 memory cells around each agent (those inside the grid)."""
        for dr in (-1, 0, 1):
            rr = rows + dr
            for dc in (-1, 0, 1):
                cc = cols + dc
                ok = (rr >= 0) & (rr < self._shape[0]) & (cc >= 0) & (cc < self._shape[1])
                self._visits[np.flatnonzero(ok), rr[ok], cc[ok]] += self.dt

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        normal, uniform = draw_per_run(rng, who, _escape_draws)
        m = len(who)
        if m == 0:
            return
        self._follow(np.asarray(who, dtype=np.int64))
        here = xy[who]
        rows, cols = self._cells(here)
        self._remember(rows, cols)
        scans = np.asarray(scans, dtype=float)
        reach = min(sensor_range, self.avoid_range)
        clear = open_directions(scans, sensor_range, reach, WIDTH_FRACTION * reach)
        angles = beam_angles(scans.shape[1])
        h = heading[who]
        # where each direction leads: the look point of a beam that sees nothing; "here" for one that sees something
        a = h[:, None] + angles[None, :]
        ends = here[:, None, :] + (LOOK_FRACTION * sensor_range) * np.stack([np.cos(a), np.sin(a)], axis=-1)
        er, ec = self._cells(ends)
        rowm = np.arange(m)[:, None]
        far = scans >= sensor_range
        seen = np.where(far, self._visits[rowm, er, ec], self._visits[rowm[:, 0], rows, cols][:, None])
        blocked = np.asarray(refused, dtype=bool) | ~clear[:, 0]
        new = clear & far & (seen < NEW_S)
        self._quiet -= self.dt
        lured = ~blocked & (self._quiet <= 0) & new.any(axis=1) & ~new[:, 0]
        self._quiet[lured] = COMMIT_S
        least = np.where(clear, seen, np.inf).min(axis=1, keepdims=True)
        weight = np.where(clear, np.exp(-np.maximum(seen - least, 0.0) / NOVELTY_S), 0.0)
        weight = np.where(lured[:, None], new, weight)
        turn = blocked | lured
        if turn.any():
            t = np.flatnonzero(turn)
            some = weight[t].sum(axis=1) > 0
            j = _pick(weight[t[some]], uniform[t[some]])
            h[t[some]] += angles[j]
            stuck = t[~some]  # nothing open around: the paper's escape heading (or turn around)
            if len(stuck):
                escape, alarmed = avoidance_heading(h[stuck], np.minimum(scans[stuck], reach), reach)
                h[stuck] = np.where(alarmed, escape, h[stuck] + np.pi)
        h = h + self.turn_noise * np.sqrt(self.dt) * normal
        heading[who] = (h + np.pi) % (2.0 * np.pi) - np.pi
