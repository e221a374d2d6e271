"""The knowledge grid the agents build together from sonar, and which of its cells are traversable.

See :mod:`amronet.algorithms.agent_assisted.explorers.frontier` for the model: evidence counts per cell (a hit adds
:data:`HIT_GAIN`,
a pass removes 1, clamped to ``[-FREE_FLOOR, OCCUPIED_CAP]``), readings that end on a known robot mark no
obstacle, and a traversable cell is a free cell with no occupied cell (nor the grid's edge, nor a deployed
node) within the clearance.

Kernels take the grid as one :class:`Cells` (:attr:`KnowledgeGrid.cells`), handed over as a plain tuple in the order
of its fields and unpacked by position: numba types a plain tuple in its compiled dispatch, a named tuple through its
class and field names (about a microsecond more per call).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.sensing import beam_angles
from amronet.world.gridwalk import walk_next, walk_start

__all__ = [
    "FREE_FLOOR",
    "HIT_GAIN",
    "OCCUPIED_CAP",
    "Cells",
    "KnowledgeGrid",
    "clearance_offsets",
    "integrate_readings",
    "is_free",
    "paint_covered",
    "paint_nodes",
    "passable",
    "trace_cells",
    "update_passable",
]

HIT_GAIN = 3
"""Evidence a beam ending in a cell adds to its count."""
OCCUPIED_CAP = 12
"""Largest evidence count (a wall needs this many grazing passes to be cleared)."""
FREE_FLOOR = 4
"""The smallest evidence count is ``-FREE_FLOOR`` (a free cell turns occupied after two hits at most)."""


class Cells(NamedTuple):
    """The knowledge grid as its kernels read and write it (see :class:`KnowledgeGrid`)."""

    score: np.ndarray
    """Evidence count per cell ``(rows, cols)`` int16; positive: occupied."""
    seen: np.ndarray
    """Whether a beam ever crossed or ended in the cell ``(rows, cols)``."""
    ox: float
    """World x of the grid's lower-left corner."""
    oy: float
    """World y of the grid's lower-left corner."""
    res: float
    """Cell size in metres."""
    row_stamp: np.ndarray
    """Per row, the stamp at which a cell of the row last changed ``(rows,)``."""


@njit(cache=True)
def trace_cells(ox, oy, res, rows, cols, x0, y0, x1, y1, out_r, out_c):  # pragma: no cover - numba
    """Cells a segment crosses, in order (Amanatides-Woo); stops at the grid's edge (compiled).

    Args:
        ox: World x of the grid's lower-left corner.
        oy: World y of the grid's lower-left corner.
        res: Cell size in metres.
        rows: Rows of the grid.
        cols: Columns of the grid.
        x0: World x of the segment's start.
        y0: World y of the segment's start.
        x1: World x of the segment's end.
        y1: World y of the segment's end.
        out_r: Gets the rows of the cells crossed; at most its length are traced.
        out_c: Gets their columns.

    Returns:
        How many cells were written to ``out_r`` and ``out_c``.
    """
    r, c, r_end, c_end, step_r, step_c, t_x, t_y, dt_x, dt_y = walk_start(ox, oy, res, x0, y0, x1, y1)
    n = 0
    while n < out_r.shape[0]:
        if r < 0 or r >= rows or c < 0 or c >= cols:
            break
        out_r[n] = r
        out_c[n] = c
        n += 1
        if r == r_end and c == c_end:
            break
        r, c, t_x, t_y, past_end = walk_next(r, c, step_r, step_c, t_x, t_y, dt_x, dt_y)
        if past_end:
            break
    return n


@njit(cache=True, inline="always")
def _near_any(x, y, pts, skip, rr2):  # pragma: no cover - numba
    """Is ``(x, y)`` within ``sqrt(rr2)`` of a row of ``pts`` other than row ``skip``?"""
    for j in range(pts.shape[0]):
        if j == skip:
            continue
        ex = x - pts[j, 0]
        ey = y - pts[j, 1]
        if ex * ex + ey * ey <= rr2:
            return True
    return False


@njit(cache=True)
def integrate_readings(cells, pos, heading, scans, angles, max_range, nodes, robot_r, buf_r, buf_c,
                       stamp):  # pragma: no cover - numba
    """Add the evidence of every beam of every sensing robot (row ``a`` of ``pos`` and ``heading``) to the grid.

    A beam's evidence is counted by :data:`HIT_GAIN`, :data:`OCCUPIED_CAP` and :data:`FREE_FLOOR`. A reading that ends
    within ``robot_r`` of another sensing robot or of one of ``nodes`` marks no obstacle (a robot's own position never
    hides its reading). ``row_stamp[r]`` becomes ``stamp`` when a cell of row ``r`` changes.

    Args:
        cells: The grid (:class:`Cells`, as a plain tuple), updated in place.
        pos: Positions of the sensing robots ``(A, 2)``.
        heading: Their headings ``(A,)``.
        scans: Their readings ``(A, n_beams)``.
        angles: The beams' angles from the heading ``(n_beams,)``.
        max_range: The sensors' range: a reading this long saw nothing.
        nodes: Other known robots ``(R, 2)``.
        robot_r: See ``nodes``.
        buf_r: Scratch rows of the cells a beam crosses (:meth:`KnowledgeGrid.buffers`).
        buf_c: Scratch columns of those cells.
        stamp: The grid's stamp for this update.
    """
    score, seen, ox, oy, res, row_stamp = cells
    hit_gain = HIT_GAIN
    cap = OCCUPIED_CAP
    floor = FREE_FLOOR
    rows, cols = score.shape
    rr2 = robot_r * robot_r
    for a in range(pos.shape[0]):
        x0 = pos[a, 0]
        y0 = pos[a, 1]
        for k in range(angles.shape[0]):
            d = min(scans[a, k], max_range)
            ang = heading[a] + angles[k]
            ux = math.cos(ang)
            uy = math.sin(ang)
            hit = d < max_range - 1e-9
            on_robot = False
            if hit:
                hx = x0 + d * ux
                hy = y0 + d * uy
                on_robot = _near_any(hx, hy, pos, a, rr2) or _near_any(hx, hy, nodes, -1, rr2)
                d += 1e-6  # the reading's point lies in the obstacle's cell
            n = trace_cells(ox, oy, res, rows, cols, x0, y0, x0 + d * ux, y0 + d * uy, buf_r, buf_c)
            last = n - 1 if hit else n
            for q in range(last):
                r = buf_r[q]
                c = buf_c[q]
                if score[r, c] > -floor:
                    score[r, c] -= 1
                    row_stamp[r] = stamp
                if not seen[r, c]:
                    seen[r, c] = True
                    row_stamp[r] = stamp
            if hit and n > 0 and not on_robot:
                r = buf_r[n - 1]
                c = buf_c[n - 1]
                new = min(score[r, c] + hit_gain, cap)
                if not seen[r, c] or new != score[r, c]:
                    seen[r, c] = True
                    score[r, c] = new
                    row_stamp[r] = stamp


@njit(cache=True)
def paint_nodes(covered, ox, oy, res, nodes, radius):  # pragma: no cover - numba
    """Set ``covered[r, c]`` where one of ``nodes`` lies within ``radius`` of the cell's centre (compiled).

    Other cells keep their value, so painting the nodes one batch after the other paints their union.

    Args:
        covered: Boolean grid ``(rows, cols)``, updated in place.
        ox: World x of the grid's lower-left corner.
        oy: World y of the grid's lower-left corner.
        res: Cell size in metres.
        nodes: Node positions ``(D, 2)`` in metres.
        radius: Disk radius in metres.
    """
    rows, cols = covered.shape
    r2 = radius * radius
    for j in range(nodes.shape[0]):
        x = nodes[j, 0]
        y = nodes[j, 1]
        c_lo = max(0, int(math.floor((x - radius - ox) / res)))
        c_hi = min(cols - 1, int(math.floor((x + radius - ox) / res)))
        r_lo = max(0, int(math.floor((y - radius - oy) / res)))
        r_hi = min(rows - 1, int(math.floor((y + radius - oy) / res)))
        for r in range(r_lo, r_hi + 1):
            dy = oy + (r + 0.5) * res - y
            for c in range(c_lo, c_hi + 1):
                dx = ox + (c + 0.5) * res - x
                if dx * dx + dy * dy <= r2:
                    covered[r, c] = True


@njit(cache=True)
def paint_covered(covered, ox, oy, res, nodes, radius):  # pragma: no cover - numba
    """``covered[r, c]``: some node lies within ``radius`` of the cell's centre (compiled).

    The arguments are those of :func:`paint_nodes`, but every cell of ``covered`` is set.
    """
    covered[:, :] = False
    paint_nodes(covered, ox, oy, res, nodes, radius)


@njit(cache=True, inline="always")
def is_free(score, seen, r, c):  # pragma: no cover - numba
    """Is cell ``(r, c)`` believed free: seen, with no positive evidence count (compiled)?"""
    return seen[r, c] and score[r, c] <= 0


@njit(cache=True)
def passable(score, seen, rb, r, c, off_r, off_c):  # pragma: no cover - numba
    """Is cell ``(r, c)`` traversable (compiled)?

    Traversable: free, not next to a known robot, and no occupied cell within the clearance (nor the grid's
    edge).

    Args:
        score: Evidence counts ``(rows, cols)`` (:attr:`KnowledgeGrid.score`).
        seen: Seen cells ``(rows, cols)`` (:attr:`KnowledgeGrid.seen`).
        rb: Cells next to known robots ``(rows, cols)``.
        r: Row of the cell (may lie outside the grid).
        c: Column of the cell.
        off_r: Row offsets of the cells within the clearance (:func:`clearance_offsets`).
        off_c: Their column offsets.
    """
    rows, cols = score.shape
    if r < 0 or r >= rows or c < 0 or c >= cols or rb[r, c] or not is_free(score, seen, r, c):
        return False
    for q in range(off_r.shape[0]):
        rr = r + off_r[q]
        cc = c + off_c[q]
        if rr < 0 or rr >= rows or cc < 0 or cc >= cols or score[rr, cc] > 0:
            return False
    return True


@njit(cache=True)
def update_passable(score, seen, rb, off_r, off_c, changed, out):  # pragma: no cover - numba
    """Bring ``out`` (:func:`passable` of every cell) up to date after the rows flagged in ``changed`` changed.

    Only the rows within the clearance of a changed row are computed again; with every row flagged, all of
    ``out`` is (compiled).

    Args:
        score: Evidence counts ``(rows, cols)``.
        seen: Seen cells ``(rows, cols)``.
        rb: Cells next to known robots ``(rows, cols)``.
        off_r: Row offsets of the cells within the clearance (:func:`clearance_offsets`).
        off_c: Their column offsets.
        changed: Rows whose ``score``, ``seen`` or ``rb`` changed since ``out`` was last brought up to date
            ``(rows,)``.
        out: Traversable cells ``(rows, cols)``, updated in place.
    """
    rows, cols = score.shape
    k = 0
    for q in range(off_r.shape[0]):
        k = max(k, abs(off_r[q]))
    for r in range(rows):
        stale = False
        for rr in range(max(0, r - k), min(rows, r + k + 1)):
            if changed[rr]:
                stale = True
                break
        if not stale:
            continue
        o = out[r]
        s_row = score[r]
        v_row = seen[r]
        b_row = rb[r]
        for c in range(cols):
            o[c] = v_row[c] and s_row[c] <= 0 and not b_row[c]
        for q in range(off_r.shape[0]):
            rr = r + off_r[q]
            dc = off_c[q]
            if rr < 0 or rr >= rows:  # the clearance reaches beyond the grid's edge
                for c in range(cols):
                    o[c] = False
                break
            s_near = score[rr]
            for c in range(cols):
                cc = c + dc
                if cc < 0 or cc >= cols or s_near[cc] > 0:
                    o[c] = False


_NO_NODES = np.zeros((0, 2))


class KnowledgeGrid:
    """What the agents know of the area: a coarse grid of unknown, free and occupied cells built from sonar.

    Args:
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
        resolution: Cell size in metres.

    Attributes:
        score: Evidence count per cell ``(rows, cols)`` int16; positive: occupied.
        seen: Whether a beam ever crossed or ended in the cell ``(rows, cols)``.
        origin: World ``(x, y)`` of the lower-left corner of cell ``(0, 0)``.
        resolution: Cell size in metres.
        stamp: How many times :meth:`integrate` added evidence.
        row_stamp: Per row, the :attr:`stamp` at which a cell of the row last changed ``(rows,)``; users that
            keep things derived from the grid bring only the rows changed since then up to date. Change
            ``score`` and ``seen`` through :meth:`integrate` only.
        cells: The grid as its kernels take it (:class:`Cells`, as a plain tuple).
    """

    def __init__(self, extent: tuple[float, float, float, float], resolution: float) -> None:
        if not resolution > 0:
            raise ValueError(f"resolution must be positive, not {resolution!r}")
        xmin, xmax, ymin, ymax = (float(v) for v in extent)
        self.origin = (xmin, ymin)
        self.resolution = float(resolution)
        cols = max(1, math.ceil((xmax - xmin) / resolution - 1e-9))
        rows = max(1, math.ceil((ymax - ymin) / resolution - 1e-9))
        self.score = np.zeros((rows, cols), dtype=np.int16)
        self.seen = np.zeros((rows, cols), dtype=np.bool_)
        self.stamp = 0
        self.row_stamp = np.zeros(rows, dtype=np.int64)
        self.cells = tuple(Cells(self.score, self.seen, xmin, ymin, self.resolution, self.row_stamp))
        self._buf_r = np.zeros(0, dtype=np.int64)
        self._buf_c = np.zeros(0, dtype=np.int64)

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)``."""
        return self.score.shape

    def buffers(self, max_range: float) -> tuple[np.ndarray, np.ndarray]:
        """Scratch cell lists long enough for a segment of ``max_range`` metres."""
        need = int(2 * math.ceil(max_range / self.resolution) + 8)
        if len(self._buf_r) < need:
            self._buf_r = np.zeros(need, dtype=np.int64)
            self._buf_c = np.zeros(need, dtype=np.int64)
        return self._buf_r, self._buf_c

    def integrate(self, xy: np.ndarray, heading: np.ndarray, scans: np.ndarray, sensor_range: float,
                  robots_xy: np.ndarray | None = None, robot_radius: float = 0.3) -> None:
        """Add the evidence of range scans.

        Args:
            xy: Positions of the sensing robots ``(A, 2)``.
            heading: Their headings ``(A,)`` (beam ``k`` points at ``heading + 2 pi k / n_beams``).
            scans: Their readings ``(A, n_beams)``.
            sensor_range: Maximum range: a reading this long saw nothing.
            robots_xy: Other known robots ``(R, 2)``: a reading ending within ``robot_radius`` of one marks
                no obstacle. The sensing robots' own positions are added (each ignores itself).
            robot_radius: See ``robots_xy``.
        """
        xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        if len(xy) == 0:
            return
        nodes = _NO_NODES if robots_xy is None else np.ascontiguousarray(robots_xy, dtype=float).reshape(-1, 2)
        buf_r, buf_c = self.buffers(sensor_range)
        integrate_readings(self.cells, xy, np.ascontiguousarray(heading, dtype=float),
                           np.ascontiguousarray(scans, dtype=float), beam_angles(scans.shape[1]), float(sensor_range),
                           nodes, float(robot_radius), buf_r, buf_c, self.stamp + 1)
        self.stamp += 1


def clearance_offsets(clearance: float, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets of the cells whose centre lies within ``clearance`` of a cell's centre (the cell itself excluded).

    Args:
        clearance: Radius in metres.
        resolution: Cell size in metres.

    Returns:
        ``(off_r, off_c)``: row and column offsets, int64.
    """
    k = int(math.floor(clearance / resolution))
    dr, dc = np.mgrid[-k:k + 1, -k:k + 1]
    keep = (dr**2 + dc**2) * resolution**2 <= clearance**2 + 1e-12
    keep &= (dr != 0) | (dc != 0)
    return dr[keep].astype(np.int64), dc[keep].astype(np.int64)
