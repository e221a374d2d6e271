"""Exact clearance to walls: point-to-square distances and the swept-disc move check, against slow references."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.motion import path_clear
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import wall_distance


def _squares(omap: OccupancyMap, pad: int = 2) -> list[tuple[float, float]]:
    """Lower-left corners of every blocked square, with a ring of off-map squares (blocked too)."""
    rows, cols = omap.shape
    res = omap.resolution
    ox, oy = omap.origin
    out = []
    for r in range(-pad, rows + pad):
        for c in range(-pad, cols + pad):
            if not (0 <= r < rows and 0 <= c < cols) or omap.cells[r, c] != 0:
                out.append((ox + c * res, oy + r * res))
    return out


def _gap_point(px, py, sx, sy, res):
    dx = max(sx - px, 0.0, px - sx - res)
    dy = max(sy - py, 0.0, py - sy - res)
    return math.hypot(dx, dy)


def _gap_segment(a, b, sx, sy, res, n=400):
    """Slow reference: the segment sampled densely, plus the square's corners against the segment."""
    ts = np.linspace(0.0, 1.0, n)
    pts = a[None, :] + ts[:, None] * (b - a)[None, :]
    g = min(_gap_point(x, y, sx, sy, res) for x, y in pts)
    v = b - a
    ll = float(v @ v)
    for cx, cy in ((sx, sy), (sx + res, sy), (sx, sy + res), (sx + res, sy + res)):
        t = 0.0 if ll == 0 else min(max(float((np.array([cx, cy]) - a) @ v) / ll, 0.0), 1.0)
        q = a + t * v
        g = min(g, math.hypot(q[0] - cx, q[1] - cy))
    return g


@st.composite
def _maps(draw):
    rows = draw(st.integers(3, 8))
    cols = draw(st.integers(3, 8))
    cells = np.array(draw(st.lists(st.sampled_from([0, 0, 0, 1, -1]), min_size=rows * cols, max_size=rows * cols)),
                     dtype=np.int8).reshape(rows, cols)
    res = draw(st.sampled_from([0.05, 0.1, 0.037, 0.25]))
    origin = (draw(st.floats(-3, 3)), draw(st.floats(-3, 3)))
    return OccupancyMap("t", res, origin, cells)


@settings(max_examples=200, deadline=None)
@given(omap=_maps(), u=st.floats(0, 1), v=st.floats(0, 1))
def test_wall_distance_is_the_exact_point_to_square_distance(omap, u, v):
    x0, x1, y0, y1 = omap.extent
    p = np.array([x0 + u * (x1 - x0), y0 + v * (y1 - y0)])
    want = min(_gap_point(p[0], p[1], sx, sy, omap.resolution) for sx, sy in _squares(omap))
    assert wall_distance(omap, p) == np.float64(want) or math.isclose(wall_distance(omap, p), want, abs_tol=1e-12)


@settings(max_examples=300, deadline=None)
@given(omap=_maps(), u=st.floats(0, 1), v=st.floats(0, 1), angle=st.floats(-math.pi, math.pi),
       length=st.floats(0, 0.3), radius=st.sampled_from([0.02, 0.045, 0.1]))
def test_a_move_is_allowed_exactly_when_the_swept_disc_keeps_its_radius(omap, u, v, angle, length, radius):
    x0, x1, y0, y1 = omap.extent
    a = np.array([x0 + u * (x1 - x0), y0 + v * (y1 - y0)])
    b = a + length * np.array([math.cos(angle), math.sin(angle)])
    squares = _squares(omap)
    start = min(_gap_point(a[0], a[1], sx, sy, omap.resolution) for sx, sy in squares)
    if start < radius + 1e-9:
        return  # a body already touching a wall: covered by the test below
    swept = min(_gap_segment(a, b, sx, sy, omap.resolution) for sx, sy in squares)
    ok = bool(path_clear(omap, a[None], b[None], np.array([radius]))[0])
    if abs(swept - radius) > 2e-3 * max(length, 1e-3):  # away from the sampling error of the reference
        assert ok == (swept >= radius), (swept, radius, ok)


def test_a_body_already_overlapping_a_wall_may_back_away_but_not_press_in():
    cells = np.zeros((10, 10), dtype=np.int8)
    cells[:, 5:] = 1  # a wall from x = 0.5 m
    omap = OccupancyMap("t", 0.1, (0.0, 0.0), cells)
    start = np.array([[0.47, 0.5]])  # a 45 mm body overlapping the wall's face by 15 mm
    r = np.array([0.045])
    assert path_clear(omap, start, np.array([[0.40, 0.5]]), r)[0]  # away: allowed
    assert not path_clear(omap, start, np.array([[0.48, 0.5]]), r)[0]  # closer: refused
    assert path_clear(omap, start, np.array([[0.47, 0.52]]), r)[0]  # along the face, no closer: allowed


def test_diagonal_approach_to_a_corner_keeps_the_body_off_it():
    # the case of the issue: centre-based clearance let a body reach a corner's square diagonally
    cells = np.zeros((20, 20), dtype=np.int8)
    cells[10:, 10:] = 1  # a block whose corner is at (0.5, 0.5) with 0.05 m cells
    omap = OccupancyMap("t", 0.05, (0.0, 0.0), cells)
    r = 0.045
    a = np.array([0.40, 0.40])
    for step in np.linspace(0.001, 0.1, 200):
        b = a + step * np.array([math.sqrt(0.5), math.sqrt(0.5)])
        if path_clear(omap, a[None], b[None], np.array([r]))[0]:
            assert wall_distance(omap, b) >= r - 1e-12
