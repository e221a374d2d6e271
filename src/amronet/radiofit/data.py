"""Measured RSSI readings, their anchors and the map: loaded, checked, and turned into link geometry.

Two CSV files with a header line:

* the readings, ``x,y,anchor,rssi_dbm`` (metres, the anchor's id, dBm) and optionally ``point``: the measurement
  (one time bin at one spot) a reading belongs to. With ``point`` the (point, anchor) pairs that have no reading
  are known: the anchor did not hear the tag (the *censored* links, see :mod:`amronet.radiofit.tobit`);
* the anchors, ``id,x,y`` and optionally ``z`` (height above the floor, metres; 0 without it).

A *spot* is one distinct ``(x, y)`` of the readings: readings taken at one spot (several bins while the robot
stood still) share their position error and their shadowing, so cross-validation and the bootstrap resample
spots, never single readings. Each link's length is 3-D (the anchor at ``z``, the tag at ``tag_height``); its
walls are counted on the 2-D line on the map by amronet's own rule (:func:`amronet.engine.walls.count_walls`:
runs of occupied or unknown cells), from the anchor to the tag.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from amronet.engine.propagation import MIN_DISTANCE_M
from amronet.engine.walls import count_walls_many, wall_grid
from amronet.errors import AmronetError
from amronet.world.occupancy import OccupancyMap

__all__ = ["RadioFitError", "Readings", "link_geometry", "load_readings"]


class RadioFitError(AmronetError):
    """Measurements that cannot be fitted: a missing column, a bad number, a point in a wall, an unknown anchor."""


@dataclass(frozen=True)
class Readings:
    """The heard readings and the censored links of a measurement campaign, as arrays.

    Attributes:
        anchor_ids: The anchors' ids as the files spell them, ``(K,)``.
        anchor_xyz: The anchors' positions ``(K, 3)`` (m).
        spot_xy: The distinct tag positions ``(S, 2)`` (m).
        spot: Spot of each reading ``(R,)``.
        anchor: Anchor index (into ``anchor_ids``) of each reading ``(R,)``.
        rssi: Received signal strength of each reading ``(R,)`` (dBm).
        d: Link length of each reading ``(R,)``: 3-D, at least :data:`MIN_DISTANCE_M` (m).
        walls: Walls crossed by each reading's 2-D line on the map ``(R,)``.
        cens_spot: Spot of each censored link (a point and an anchor that has no reading there) ``(C,)``.
        cens_anchor: Anchor index of each censored link ``(C,)``.
        cens_d: Link length of each censored link ``(C,)``.
        cens_walls: Walls of each censored link ``(C,)``.
        has_points: Whether the readings file had a ``point`` column (otherwise nothing is known to be censored).
        tag_height: Height of the tag above the floor (m).
    """

    anchor_ids: np.ndarray
    anchor_xyz: np.ndarray
    spot_xy: np.ndarray
    spot: np.ndarray
    anchor: np.ndarray
    rssi: np.ndarray
    d: np.ndarray
    walls: np.ndarray
    cens_spot: np.ndarray
    cens_anchor: np.ndarray
    cens_d: np.ndarray
    cens_walls: np.ndarray
    has_points: bool
    tag_height: float

    @property
    def n_spots(self) -> int:
        """Number of distinct tag positions."""
        return len(self.spot_xy)

    @property
    def n_anchors(self) -> int:
        """Number of anchors."""
        return len(self.anchor_ids)


def _read_table(path: str | Path, option: str, required: tuple[str, ...],
                optional: tuple[str, ...] = ()) -> dict[str, np.ndarray]:
    """The named columns of a CSV file as arrays of strings; a problem is one line naming the file and the fix."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not a UTF-8 text file"
        raise RadioFitError(f"{option}: cannot read {str(path)!r}: {reason}") from None
    rows = [r for r in rows if any(cell.strip() for cell in r)]
    want = ",".join(required)
    if not rows:
        raise RadioFitError(f"{option}: {str(path)!r} is empty; give a CSV file with the header {want}")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in required if c not in header]
    if missing:
        raise RadioFitError(f"{option}: {str(path)!r} has no column {missing[0]!r} (header: {','.join(header)}); "
                            f"give a CSV file with the columns {want}")
    if len(rows) == 1:
        raise RadioFitError(f"{option}: {str(path)!r} has a header but no rows; give at least one row")
    out = {}
    for name in required + tuple(c for c in optional if c in header):
        j = header.index(name)
        try:
            out[name] = np.array([r[j].strip() for r in rows[1:]], dtype=object)
        except IndexError:
            bad = next(i for i, r in enumerate(rows[1:], start=2) if len(r) <= j)
            raise RadioFitError(f"{option}: {str(path)!r} line {bad} has too few fields; give every column") from None
    return out


def _numbers(path: str | Path, option: str, name: str, text: np.ndarray) -> np.ndarray:
    """A column as finite floats; a bad value is one line naming its line number."""
    try:
        values = text.astype(float)
    except ValueError:
        bad = next(i for i, t in enumerate(text) if not _is_float(t))
        raise RadioFitError(f"{option}: {str(path)!r} line {bad + 2}: {name} = {text[bad]!r} is not a number; "
                            "fix or remove that row") from None
    finite = np.isfinite(values)
    if not finite.all():
        bad = int(np.flatnonzero(~finite)[0])
        raise RadioFitError(f"{option}: {str(path)!r} line {bad + 2}: {name} = {text[bad]!r} is not finite; "
                            "remove that row (an anchor that did not hear the tag has no row)")
    return values


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def link_geometry(omap: OccupancyMap, anchor_xyz: np.ndarray, tag_xy: np.ndarray, tag_height: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """3-D lengths and 2-D wall counts of the links from anchors ``anchor_xyz (M, 3)`` to tags ``tag_xy (M, 2)``."""
    a = np.ascontiguousarray(anchor_xyz[:, :2], dtype=float)
    b = np.ascontiguousarray(tag_xy, dtype=float)
    dz = anchor_xyz[:, 2] - tag_height
    d = np.maximum(np.sqrt(np.sum((a - b) ** 2, axis=1) + dz * dz), MIN_DISTANCE_M)
    cells, jump = wall_grid(omap)
    limit = np.full(len(a), 1 << 30, dtype=np.int64)
    walls = count_walls_many(cells, jump, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
                             a, b, limit)
    return d, walls.astype(float)


def _check_on_map(omap: OccupancyMap, xy: np.ndarray, option: str, what: str, labels: np.ndarray) -> None:
    inside, free = omap.inside(xy), omap.is_free(xy)
    for ok, problem in ((inside, "is off the map"), (free, "is in a wall or unknown space of the map")):
        if not ok.all():
            k = int(np.flatnonzero(~ok)[0])
            x0, x1, y0, y1 = omap.extent
            raise RadioFitError(f"{option}: {what} {labels[k]} at ({xy[k, 0]:g}, {xy[k, 1]:g}) {problem} "
                                f"{omap.name} [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}]; {sum(~ok)} such rows: "
                                "check the frame, or drop them")


def load_readings(omap: OccupancyMap, anchors_path: str | Path, rssi_path: str | Path,
                  tag_height: float = 0.0) -> Readings:
    """Load and check the anchors and readings, and compute every link's length and walls on ``omap``.

    Raises:
        RadioFitError: A file is missing, empty, lacks a column or holds a bad value; an id is repeated or
            unknown; a point or an anchor is off the map or in a wall (one line naming the file and the fix).
    """
    at = _read_table(anchors_path, "--anchors", ("id", "x", "y"), ("z",))
    ids = np.array([s for s in at["id"]], dtype=object)
    if len(set(ids)) != len(ids):
        dup = next(i for i in ids if list(ids).count(i) > 1)
        raise RadioFitError(f"--anchors: anchor id {dup!r} appears twice; give each anchor once")
    axyz = np.zeros((len(ids), 3))
    for j, c in enumerate(("x", "y", "z")):
        if c in at:
            axyz[:, j] = _numbers(anchors_path, "--anchors", c, at[c])
    _check_on_map(omap, axyz[:, :2], "--anchors", "anchor", ids)
    rt = _read_table(rssi_path, "--rssi", ("x", "y", "anchor", "rssi_dbm"), ("point",))
    xy = np.stack([_numbers(rssi_path, "--rssi", c, rt[c]) for c in ("x", "y")], axis=1)
    rssi = _numbers(rssi_path, "--rssi", "rssi_dbm", rt["rssi_dbm"])
    index = {a: k for k, a in enumerate(ids)}
    unknown = [a for a in rt["anchor"] if a not in index]
    if unknown:
        raise RadioFitError(f"--rssi: anchor {unknown[0]!r} is not in --anchors ({len(unknown)} rows); known ids: "
                            f"{', '.join(ids)}")
    anchor = np.array([index[a] for a in rt["anchor"]], dtype=np.int64)
    _check_on_map(omap, xy, "--rssi", "line", np.arange(2, len(xy) + 2))
    spot_xy, spot = np.unique(xy, axis=0, return_inverse=True)
    spot = spot.reshape(-1)
    d, walls = link_geometry(omap, axyz[anchor], xy, tag_height)
    cens = _censored(rt.get("point"), rssi_path, spot, anchor, len(ids))
    cs, ca = cens
    cd, cw = link_geometry(omap, axyz[ca], spot_xy[cs], tag_height) if len(cs) else (np.zeros(0), np.zeros(0))
    return Readings(np.array(ids, dtype=str), axyz, spot_xy, spot, anchor, rssi, d, walls, cs, ca, cd, cw,
                    "point" in rt, float(tag_height))


def _censored(points: np.ndarray | None, path: str | Path, spot: np.ndarray, anchor: np.ndarray, k: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """Spots and anchors of the (point, anchor) pairs without a reading; none without a ``point`` column."""
    if points is None:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    pid, pt = np.unique(points, return_inverse=True)
    pt = pt.reshape(-1)
    first = np.full(len(pid), -1, np.int64)
    first[pt[::-1]] = spot[::-1]
    if np.any(first[pt] != spot):
        bad = int(np.flatnonzero(first[pt] != spot)[0])
        raise RadioFitError(f"--rssi: {str(path)!r} line {bad + 2}: point {points[bad]} has rows at two different "
                            "positions; give each point one x,y")
    heard = np.zeros((len(pid), k), dtype=np.int64)
    np.add.at(heard, (pt, anchor), 1)
    if heard.max() > 1:
        p, a = np.argwhere(heard > 1)[0]
        raise RadioFitError(f"--rssi: point {pid[p]} has {heard[p, a]} rows for one anchor; give one reading per "
                            "point and anchor")
    p, a = np.nonzero(heard == 0)
    return first[p], a.astype(np.int64)
