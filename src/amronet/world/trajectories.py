"""Agents' paths given by the user (``agents.trajectories``): a CSV of timed waypoints, read and checked once.

The file has a header row naming the four columns ``t, agent, x, y`` (in any order, names case-insensitive) and
one waypoint per row::

    # a planned mission: agent 0 goes down the corridor, waits in the doorway, comes back
    t,agent,x,y
    0,0,2.0,2.0
    30,0,16.0,2.0
    60,0,16.0,2.0
    90,0,2.0,2.0

* ``t``: seconds from the start of the run (``t = 0``), at least 0; an agent's rows are in time order
  (non-decreasing; rows of different agents may be interleaved).
* ``agent``: the agent's index ``0 .. A-1`` in creation order, ``A = agents.per_base`` times the number of base
  stations: base station ``b``'s agents are ``b * per_base .. (b + 1) * per_base - 1``, in the order of
  ``base_stations``.
* ``x``, ``y``: metres in the map's own frame (what ``network.json`` reports); every point lies inside the map, in
  a free cell, in free space reachable from the base stations.

Blank lines and lines starting with ``#`` are skipped. Every check fails with one line that names the field, the
file, the line and the fix (:class:`~amronet.errors.ScenarioError`). An agent without rows has no path.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amronet.errors import ScenarioError
from amronet.world.occupancy import OccupancyMap

__all__ = ["COLUMNS", "AgentPaths", "load_trajectories"]

COLUMNS: tuple[str, ...] = ("t", "agent", "x", "y")
"""The columns of a trajectory file (any order)."""

FIELD = "agents.trajectories"


@dataclass(frozen=True)
class AgentPaths:
    """The agents' paths, row by row, grouped by agent (within an agent in time order).

    Attributes:
        t: Waypoint times ``(K,)``, seconds from the start of the run.
        xy: Waypoint positions ``(K, 2)``, metres in the map's frame.
        start: ``(A + 1,)`` offsets: agent ``a``'s waypoints are rows ``start[a]:start[a + 1]`` (none: no path).
        source: The file the paths came from (for messages).
    """

    t: np.ndarray
    xy: np.ndarray
    start: np.ndarray
    source: str = ""

    @property
    def n_agents(self) -> int:
        """How many agents the paths are for (those without a path included)."""
        return len(self.start) - 1

    @property
    def has_path(self) -> np.ndarray:
        """Which agents have at least one waypoint ``(A,)``."""
        return self.start[1:] > self.start[:-1]


def _fail(shown: str, where: str, message: str) -> ScenarioError:
    return ScenarioError(FIELD, f"{shown}{where}: {message}")


def _number(text: str, name: str, shown: str, line: int, unit: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise _fail(shown, f" line {line}", f"{name} {text!r} is not a number; give {unit}") from None
    if not math.isfinite(value):
        raise _fail(shown, f" line {line}", f"{name} is {text.strip()}; give a finite number ({unit})")
    return value


def _agent_id(text: str, shown: str, line: int, n_agents: int) -> int:
    try:
        return int(text)
    except ValueError:
        value = _number(text, "agent", shown, line, f"an agent index 0..{n_agents - 1}")
        if not value.is_integer():
            raise _fail(shown, f" line {line}", f"agent {text.strip()} is not an integer; give an agent index "
                                                f"0..{n_agents - 1}") from None
        return int(value)


def _header(row: list[str], shown: str, line: int) -> list[int]:
    """The positions of ``t, agent, x, y`` in the header row."""
    names = [c.strip().lower() for c in row]
    unknown = [c for c in names if c not in COLUMNS]
    if unknown:
        raise _fail(shown, f" line {line}", f"unknown column {unknown[0]!r} in the header; the columns are exactly "
                                            "t, agent, x, y (any order)")
    twice = sorted({c for c in names if names.count(c) > 1})
    if twice:
        raise _fail(shown, f" line {line}", f"column {twice[0]!r} appears twice in the header; give each of t, agent, "
                                            "x, y once")
    missing = [c for c in COLUMNS if c not in names]
    if missing:
        raise _fail(shown, f" line {line}", f"the header lacks column{'s' if len(missing) > 1 else ''} "
                                            f"{', '.join(missing)}; the first row names the columns t, agent, x, y")
    return [names.index(c) for c in COLUMNS]


def _read_rows(path: Path, shown: str, n_agents: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Parse the file: ``(t, agent, xy, line)`` per waypoint, in file order; each value checked on its own."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise _fail(shown, "", f"cannot read the file ({type(exc).__name__}); give a readable UTF-8 CSV") from None
    cols: list[int] | None = None
    t: list[float] = []
    agent: list[int] = []
    xy: list[tuple[float, float]] = []
    lines: list[int] = []
    try:
        for line, row in enumerate(csv.reader(text.splitlines()), start=1):
            if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
                continue
            if cols is None:
                cols = _header(row, shown, line)
                continue
            if len(row) != len(COLUMNS):
                raise _fail(shown, f" line {line}", f"{len(row)} value{'s' if len(row) != 1 else ''}, but the "
                                                    "header has 4 columns; give t, agent, x, y on every row")
            vals = [row[c] for c in cols]
            t.append(_number(vals[0], "t", shown, line, "seconds from the start of the run"))
            agent.append(_agent_id(vals[1], shown, line, n_agents))
            xy.append((_number(vals[2], "x", shown, line, "metres"), _number(vals[3], "y", shown, line, "metres")))
            lines.append(line)
    except csv.Error as exc:
        raise _fail(shown, "", f"not a valid CSV ({exc}); give comma-separated t, agent, x, y") from None
    if cols is None:
        raise _fail(shown, "", "the file is empty; give a header t, agent, x, y and one waypoint per row")
    if not t:
        raise _fail(shown, "", "no waypoints after the header; add rows t, agent, x, y")
    return (np.asarray(t, dtype=float), np.asarray(agent, dtype=np.int64), np.asarray(xy, dtype=float).reshape(-1, 2),
            np.asarray(lines, dtype=np.int64))


def _check_agents(agent: np.ndarray, lines: np.ndarray, shown: str, n_agents: int) -> None:
    bad = np.flatnonzero((agent < 0) | (agent >= n_agents))
    if len(bad):
        k = bad[0]
        known = f"0..{n_agents - 1}" if n_agents > 1 else "0"
        raise _fail(shown, f" line {lines[k]}", f"unknown agent {agent[k]}; the scenario has {n_agents} agent"
                                                f"{'s' if n_agents != 1 else ''} ({known}: agents.per_base per base "
                                                "station, numbered in the order of base_stations)")


def _check_times(t: np.ndarray, agent: np.ndarray, lines: np.ndarray, shown: str,
                 time_limit: float | None) -> np.ndarray:
    """Check the times; the order that groups the rows by agent, each agent's rows in file (= time) order."""
    negative = np.flatnonzero(t < 0)
    if len(negative):
        k = negative[0]
        raise _fail(shown, f" line {lines[k]}", f"t = {t[k]:g} s is negative; times are seconds from the start of "
                                                "the run (t = 0): shift them")
    order = np.argsort(agent, kind="stable")
    same = agent[order][1:] == agent[order][:-1]
    back = np.flatnonzero(same & (np.diff(t[order]) < 0))
    if len(back):
        # the first offending line of the file, and the row of the same agent just before it
        k = back[np.argmin(lines[order][back + 1])]
        prev, cur = order[k], order[k + 1]
        raise _fail(shown, f" line {lines[cur]}", f"t = {t[cur]:g} s for agent {agent[cur]} comes after t = "
                                                  f"{t[prev]:g} s at line {lines[prev]}; sort each agent's rows "
                                                  "by time")
    if time_limit is not None:
        first = order[np.concatenate([[True], ~same])]
        late = first[t[first] > time_limit]
        if len(late):
            k = late[np.argmin(lines[late])]
            raise _fail(shown, f" line {lines[k]}", f"agent {agent[k]}'s path starts at t = {t[k]:g} s, after "
                                                    f"sim.time_limit ({time_limit:g} s); times are seconds from the "
                                                    "start of the run (t = 0): shift them or raise sim.time_limit")
    return order


def _check_points(xy: np.ndarray, lines: np.ndarray, shown: str, omap: OccupancyMap,
                  reachable: np.ndarray | None) -> None:
    xmin, xmax, ymin, ymax = omap.extent
    pad = omap.resolution  # points farther out are outside: the map's cell arithmetic never sees them (1e300)
    near = ((xy[:, 0] >= xmin - pad) & (xy[:, 0] <= xmax + pad) & (xy[:, 1] >= ymin - pad) & (xy[:, 1] <= ymax + pad))
    inside, free = np.zeros(len(xy), dtype=bool), np.zeros(len(xy), dtype=bool)
    inside[near], free[near] = omap.inside(xy[near]), omap.is_free(xy[near])
    ok = free.copy()
    if reachable is not None:
        rows, cols = omap.world_to_cell(xy[free])
        ok[free] = reachable[rows, cols]
    bad = np.flatnonzero(~ok)
    if not len(bad):
        return
    k = bad[0]
    where = f"({xy[k, 0]:g}, {xy[k, 1]:g})"
    if not inside[k]:
        why = f"{where} is outside the map [{xmin:g}, {xmax:g}] x [{ymin:g}, {ymax:g}]"
    elif not free[k]:
        why = f"{where} is inside a wall or unknown space"
    else:
        why = f"{where} is free space that cannot be reached from the base stations"
    raise _fail(shown, f" line {lines[k]}", f"{why}; move the waypoint into the free space of map "
                                            f"'{omap.name}' (metres in the map's frame)")


def load_trajectories(path: str | Path, omap: OccupancyMap, n_agents: int, *, reachable: np.ndarray | None = None,
                      time_limit: float | None = None, shown: str | None = None) -> AgentPaths:
    """Read and check a trajectory file (the format is in the module docstring).

    Args:
        path: The CSV file.
        omap: The scenario's map: every waypoint must lie inside it, in a free cell.
        n_agents: How many agents the scenario has (ids are ``0 .. n_agents - 1``).
        reachable: Optional mask of the free cells reachable from the base stations (the map's shape); given,
            every waypoint must lie in one.
        time_limit: Optional ``sim.time_limit``: no agent's path may start after it (a file of clock times
            rather than seconds from the start would have every agent wait for the whole run).
        shown: How the file is named in messages (default: ``path``).

    Returns:
        The paths, grouped by agent.

    Raises:
        ScenarioError: The file cannot be read or breaks a rule; one line naming ``agents.trajectories``, the file,
            the line and the fix.
    """
    path = Path(path)
    shown = str(path) if shown is None else shown
    t, agent, xy, lines = _read_rows(path, shown, n_agents)
    _check_agents(agent, lines, shown, n_agents)
    order = _check_times(t, agent, lines, shown, time_limit)
    _check_points(xy, lines, shown, omap, reachable)
    counts = np.bincount(agent, minlength=n_agents)
    start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return AgentPaths(t=t[order], xy=xy[order], start=start, source=shown)
