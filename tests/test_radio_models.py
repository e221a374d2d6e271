"""Tests of the radio models (unit-disk, log-distance, multi-wall): link budget, walls, coverage, runs, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp

from amronet.cli import main
from amronet.engine.coverage import CoverageArea
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.network import connected_to
from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget, delivery_ratio, median_range
from amronet.engine.radio import LogDistance, MultiWall, UnitDisk, make_medium
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim.simulation import Simulation
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap

PRESET = "self-spreading-obstacles-6x6"


def open_map(rows: int = 80, cols: int = 80, res: float = 0.125, origin=(-5.0, -5.0)) -> OccupancyMap:
    return OccupancyMap("open", res, origin, np.zeros((rows, cols), dtype=np.int8))


def wall_map(wall_cols=(slice(40, 41),), rows: int = 40, cols: int = 80, res: float = 0.125) -> OccupancyMap:
    """A free 10 m x 5 m strip of 0.125 m cells, origin (0, 0), with full-height walls at the given columns."""
    cells = np.zeros((rows, cols), dtype=np.int8)
    for s in wall_cols:
        cells[:, s] = OCCUPIED
    return OccupancyMap("walls", res, (0.0, 0.0), cells)


def budget(r_c: float = 2.0, n: float = 2.0, wall_db: float = 0.0, shadowing_db: float = 0.0) -> LinkBudget:
    return LinkBudget(r_c=r_c, exponent=n, wall_db=wall_db, shadowing_db=shadowing_db)


def rows_of(table) -> np.ndarray:
    return np.repeat(np.arange(len(table.xy)), table.degree)


def pair_margin(table, i: int, j: int) -> float | None:
    """The margin of link (i, j) in the table, ``None`` if there is no such link."""
    row = table.indices[table.indptr[i]:table.indptr[i + 1]]
    hit = np.flatnonzero(row == j)
    return None if len(hit) == 0 else float(table.margin[table.indptr[i] + hit[0]])


def pair_rssi(table, i: int, j: int) -> float | None:
    m = pair_margin(table, i, j)
    return None if m is None else table.threshold_dbm + m


# -- the link budget ---------------------------------------------------------------------------------------
def test_calibration_threshold_and_median_range():
    b = LinkBudget(r_c=3.0, tx_dbm=17.0, pl0_db=38.0, exponent=2.7)
    assert b.threshold_dbm == pytest.approx(17.0 - 38.0 - 27.0 * math.log10(3.0), abs=1e-12)
    assert median_range(b.tx_dbm, b.pl0_db, b.exponent, b.threshold_dbm) == pytest.approx(3.0, rel=1e-12)
    assert float(b.margin_db(3.0)) == pytest.approx(0.0, abs=1e-12)
    assert float(b.rssi_dbm(3.0)) == pytest.approx(b.threshold_dbm, abs=1e-12)
    # tx_dbm and pl0_db shift every RSSI but decide no link: the margin does not depend on them
    b2 = LinkBudget(r_c=3.0, tx_dbm=0.0, pl0_db=60.0, exponent=2.7)
    d = np.array([0.1, 1.0, 2.9, 3.0, 3.1, 10.0])
    np.testing.assert_allclose(b.margin_db(d), b2.margin_db(d), atol=1e-12)
    np.testing.assert_allclose(b.rssi_dbm(d) - b2.rssi_dbm(d), 17.0 - 38.0 - (0.0 - 60.0), atol=1e-9)
    # RSSI falls by 10 n dB per decade; a wall costs wall_db; links shorter than 1 cm count as 1 cm
    w = LinkBudget(r_c=3.0, exponent=2.7, wall_db=6.9)
    assert float(w.rssi_dbm(0.3) - w.rssi_dbm(3.0)) == pytest.approx(27.0)
    assert float(w.margin_db(1.0, walls=2) - w.margin_db(1.0)) == pytest.approx(-13.8)
    assert float(w.margin_db(0.0)) == float(w.margin_db(MIN_DISTANCE_M))
    assert b.reach == 3.0 and LinkBudget(r_c=1.0, exponent=2.5, shadowing_db=5.0).reach == pytest.approx(10 ** 0.6)


def test_delivery_ratio_curve():
    assert float(delivery_ratio(0.0)) == pytest.approx(0.9, abs=1e-9)
    m = np.linspace(-10, 10, 2001)
    p = delivery_ratio(m)
    assert (np.diff(p) >= 0).all() and (np.diff(p[(m > -6) & (m < 3)]) > 0).all()
    assert p[0] < 1e-6 and p[-1] == pytest.approx(1.0, abs=1e-12)
    # half the packets get through about 1.6 dB below the threshold (exactly at -1.675 dB: 0.524 at -1.6 dB)
    assert float(delivery_ratio(-1.6)) == pytest.approx(0.5, abs=0.03)
    half = m[np.argmin(np.abs(p - 0.5))]
    assert -1.75 < half < -1.6
    assert float(delivery_ratio(2.0)) == pytest.approx(0.997, abs=0.002)
    assert float(delivery_ratio(4.0)) > 1 - 1e-4
    assert ((p >= 0) & (p <= 1)).all()


# -- analytic checks of the media --------------------------------------------------------------------------
@pytest.mark.parametrize("model", ["log-distance", "multi-wall"])
def test_without_walls_or_shadowing_margins_are_the_closed_form(model):
    """Links exist exactly for d <= r_c (the median range is r_c) and their margin is 10 n log10(r_c / d)."""
    r_c, n = 2.0, 2.7
    omap = open_map()
    medium = make_medium(model, budget(r_c, n, wall_db=6.9 if model == "multi-wall" else 0.0), omap)
    rng = np.random.default_rng(4)
    xy = rng.uniform(-4.0, 4.0, (300, 2))  # well inside the 10 m x 10 m map: no wall (nor outside) in between
    # and pairs right at the boundary: exactly r_c apart along an axis, and a hair inside / outside
    xy = np.vstack([xy, [[0.01, 0.02], [0.01 + r_c, 0.02], [0.01, 0.52], [0.01 + r_c * (1 - 1e-9), 0.52],
                         [0.01, 1.02], [0.01 + r_c * (1 + 1e-9), 1.02]]])
    table = medium.update(xy)
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    np.fill_diagonal(d, np.inf)
    want = {(i, j) for i, j in zip(*np.nonzero(d <= r_c), strict=True) if i < j}
    assert {tuple(p) for p in table.pairs.tolist()} == want
    k = len(xy) - 6
    assert pair_margin(table, k, k + 1) == pytest.approx(0.0, abs=1e-12)
    assert pair_margin(table, k + 2, k + 3) is not None and pair_margin(table, k + 4, k + 5) is None
    np.testing.assert_allclose(table.margin, 10 * n * np.log10(r_c / table.dist), rtol=0, atol=1e-9)
    np.testing.assert_allclose(table.rssi, medium.budget.threshold_dbm + table.margin, rtol=0, atol=1e-12)
    np.testing.assert_allclose(table.delivery, delivery_ratio(table.margin))
    assert table.delivery.min() >= 0.9 - 1e-9


def test_one_wall_costs_exactly_wall_db():
    r_c, n, wall_db = 20.0, 2.0, 6.9
    omap = wall_map([slice(40, 41), slice(60, 64)])  # a thin wall at x 5.0..5.125, a thick one at 7.5..8.0
    # pairs: across the thin wall, across the thick wall, across both, and in the free room (none)
    xy = np.array([[4.53, 2.51], [5.71, 2.37],   # 0-1: one thin wall
                   [7.13, 1.21], [8.42, 1.47],   # 2-3: one thick wall (four cells) counts once
                   [4.81, 3.33], [8.36, 3.61],   # 4-5: both walls
                   [1.11, 1.12], [2.33, 2.01]])  # 6-7: none
    log = make_medium("log-distance", budget(r_c, n), omap)
    multi = make_medium("multi-wall", budget(r_c, n, wall_db=wall_db), omap)
    tl, tm = log.update(xy), multi.update(xy)
    assert tl.threshold_dbm == tm.threshold_dbm
    for (i, j), walls in {(0, 1): 1, (2, 3): 1, (4, 5): 2, (6, 7): 0}.items():
        assert pair_rssi(tm, i, j) is not None, (i, j)
        assert pair_rssi(tl, i, j) - pair_rssi(tm, i, j) == pytest.approx(walls * wall_db, abs=1e-9)
        assert pair_rssi(tm, j, i) == pair_rssi(tm, i, j)
    # a link whose budget cannot pay for its wall is gone under multi-wall (and kept by the geometric view)
    far = np.array([[4.53, 2.51], [7.0, 2.37]])  # 2.47 m at r_c = 4: margin 4.2 dB < 6.9 dB
    assert len(make_medium("log-distance", budget(4.0, n), omap).update(far).pairs) == 1
    tfar = make_medium("multi-wall", budget(4.0, n, wall_db=wall_db), omap).update(far)
    assert len(tfar.pairs) == 0 and len(tfar.geometric.pairs) == 1
    d = float(np.hypot(*(far[1] - far[0])))
    assert tfar.geometric.margin[0] == pytest.approx(20 * math.log10(4.0 / d) - wall_db, abs=1e-9)


def test_link_along_a_wall_face_crosses_none():
    r_c, n = 3.0, 2.0
    cells = np.zeros((40, 80), dtype=np.int8)
    cells[16:24, 24:56] = OCCUPIED  # a block at x 3.0..7.0, y 2.0..3.0 (0.125 m cells)
    omap = OccupancyMap("block", 0.125, (0.0, 0.0), cells)
    xy = np.array([[3.5, 2.0], [5.5, 2.0],    # along the lower face
                   [4.0, 3.0], [6.25, 3.0],   # along the upper face
                   [3.0, 1.2], [3.0, 3.9],    # along the left face
                   [4.0, 2.0 - 0.01], [6.0, 2.0 + 0.01]])  # a hair across it: one wall
    multi = make_medium("multi-wall", budget(r_c, n, wall_db=10.0), omap).update(xy)
    log = make_medium("log-distance", budget(r_c, n), omap).update(xy)
    for i, j in ((0, 1), (2, 3), (4, 5)):
        assert pair_margin(multi, i, j) == pytest.approx(pair_margin(log, i, j), abs=1e-9), (i, j)
    assert pair_margin(multi, 6, 7) is None or pair_margin(log, 6, 7) - pair_margin(multi, 6, 7) == pytest.approx(10)
    assert pair_margin(multi.geometric, 6, 7) == pytest.approx(pair_margin(log, 6, 7) - 10.0, abs=1e-9)


def test_tables_are_symmetric_including_rssi():
    omap = resolve_map("office-32x32")
    rng = np.random.default_rng(8)
    free = np.argwhere(omap.cells == FREE)
    pick = free[rng.choice(len(free), 400, replace=False)]
    xy = np.column_stack([omap.origin[0] + (pick[:, 1] + rng.random(400)) * omap.resolution,
                          omap.origin[1] + (pick[:, 0] + rng.random(400)) * omap.resolution])
    cases = [("unit-disk", budget(2.0, 2.5), False), ("log-distance", budget(2.0, 2.5, shadowing_db=6.0), False),
             ("multi-wall", budget(3.0, 2.0, wall_db=4.0, shadowing_db=4.0), False),
             ("multi-wall", budget(3.0, 2.0, wall_db=4.0, shadowing_db=4.0), True)]
    n = len(xy)
    for model, b, loss in cases:
        medium = make_medium(model, b, omap, rng=np.random.default_rng(1), packet_loss=loss)
        table = medium.update(xy)
        for t in (table, table.geometric):
            for data in (t.dist, t.rssi, t.margin, t.delivery):
                a = sp.csr_matrix((data, t.indices, t.indptr), shape=(n, n))
                assert (a != a.T).nnz == 0, (model, loss)
            assert (np.diff(t.indices) > 0)[np.diff(rows_of(t)) == 0].all()  # rows sorted, no duplicates
        assert len(table.pairs) > 100, model
        if model == "multi-wall":
            assert len(table.pairs) < len(table.geometric.pairs)  # walls cut links


def test_coincident_nodes_and_nodes_on_cell_centres():
    """Two nodes at one spot are linked (as 1 cm apart) under every model; a node on a cell centre hears it."""
    omap = open_map(rows=40, cols=40, res=0.05, origin=(0.0, 0.0))
    xy = np.array([[1.01, 1.01], [1.01, 1.01], [0.33, 0.41]])
    area = CoverageArea(omap, omap.free)
    centre = 0.0 + (20 + 0.5) * 0.05  # exactly the centre of cell (20, 20) as the kernels compute it
    for model in ("unit-disk", "log-distance", "multi-wall"):
        medium = make_medium(model, budget(1.0, 2.0, wall_db=6.9 if model == "multi-wall" else 0.0), omap)
        table = medium.update(xy)
        assert pair_margin(table, 0, 1) == pytest.approx(20 * math.log10(1.0 / MIN_DISTANCE_M))
        covered = medium.covered_mask(area, np.array([[centre, centre]]))
        assert covered[20, 20]
        assert medium.coverage(area, np.array([[centre, centre]])) == pytest.approx(covered.sum() / area.n_cells)


def test_packet_loss_drops_links_by_their_delivery_ratio():
    omap = open_map()
    xy = np.random.default_rng(2).uniform(-4.0, 4.0, (400, 2))
    b = budget(2.0, 2.5)
    full = make_medium("log-distance", b, omap).update(xy)
    lossy = make_medium("log-distance", b, omap, rng=np.random.default_rng(3), packet_loss=True)
    full_pairs = {tuple(p) for p in full.pairs.tolist()}
    upper = full.indices > rows_of(full)
    np.testing.assert_array_equal(full.pairs, np.column_stack([rows_of(full)[upper], full.indices[upper]]))
    margin = {tuple(p): m for p, m in zip(full.pairs.tolist(), full.margin[upper], strict=True)}
    kept = np.zeros(len(full_pairs))
    steps = 20
    keys = sorted(full_pairs)
    for _ in range(steps):
        t = lossy.update(xy)
        pairs = {tuple(p) for p in t.pairs.tolist()}
        assert pairs <= full_pairs
        kept += np.array([k in pairs for k in keys])
    p = delivery_ratio(np.array([margin[k] for k in keys]))
    # every pair is an independent Bernoulli(p) per step: the total kept is close to its expectation
    expected, var = steps * p.sum(), steps * (p * (1 - p)).sum()
    assert abs(kept.sum() - expected) < 5 * math.sqrt(var)
    assert (kept[p > 1 - 1e-12] == steps).all()


# -- the unit disk is unchanged ----------------------------------------------------------------------------
def test_unit_disk_table_is_neighbour_csr():
    rng = np.random.default_rng(0)
    for n, r_c in ((0, 1.0), (1, 1.0), (200, 0.7), (500, 1.3)):
        xy = rng.uniform(-3, 3, (n, 2))
        table = make_medium("unit-disk", r_c).update(xy)
        indptr, indices, dist = neighbour_csr(xy, r_c)
        for got, want in ((table.indptr, indptr), (table.indices, indices), (table.dist, dist)):
            assert got.dtype == want.dtype
            np.testing.assert_array_equal(got, want)
        assert table.candidates is None and table.geometric is table and table.r == r_c
        np.testing.assert_allclose(table.margin, 25 * np.log10(r_c / np.maximum(dist, MIN_DISTANCE_M)), atol=1e-12)


def test_unit_disk_coverage_is_eq_1():
    omap = resolve_map("obstacles-6x6")
    area = CoverageArea(omap, omap.free)
    rng = np.random.default_rng(1)
    for r_c in (0.6, 1.0):
        medium = make_medium("unit-disk", r_c, omap)
        for n in (1, 7, 30):
            xy = rng.uniform(-3.2, 3.2, (n, 2))
            assert medium.coverage(area, xy) == area.fraction(xy, r_c)
            assert medium.coverage(area, xy, method="exact") == area.fraction(xy, r_c, method="exact")
            np.testing.assert_array_equal(medium.covered_mask(area, xy), area.covered_mask(xy, r_c))
    for model in ("log-distance", "multi-wall"):
        with pytest.raises(ValueError, match="raster"):
            make_medium(model, budget(1.0, 2.0), omap).coverage(area, xy, method="exact")


# -- coverage under a radio ----------------------------------------------------------------------------------
def test_coverage_multi_wall_below_log_distance_equal_to_unit_disk():
    omap = resolve_map("obstacles-6x6")
    area = CoverageArea(omap, omap.free)
    rng = np.random.default_rng(5)
    r_c = 0.9
    unit = make_medium("unit-disk", r_c, omap)
    log = make_medium("log-distance", budget(r_c, 2.5), omap)
    multi = make_medium("multi-wall", budget(r_c, 2.0, wall_db=6.9), omap)
    strict_below = 0
    for n in (1, 5, 20, 40):
        for _ in range(5):
            xy = rng.uniform(-3.0, 3.0, (n, 2))
            cu, cl, cm = unit.covered_mask(area, xy), log.covered_mask(area, xy), multi.covered_mask(area, xy)
            # the unit disk tests d^2 <= r_c^2 at the cell centres, the path-loss models 10 n log10(r_c / d) >= 0:
            # the two differ only for a centre within a rounding error of the circle, a measure-zero event that
            # none of these random positions hits, so equality is exact
            np.testing.assert_array_equal(cl, cu)
            assert log.coverage(area, xy) == unit.coverage(area, xy)
            assert not (cm & ~cl).any()  # walls only take away
            assert multi.coverage(area, xy) <= log.coverage(area, xy)
            assert multi.coverage(area, xy) == cm.sum() / area.n_cells
            strict_below += int(cm.sum() < cl.sum())
    assert strict_below >= 10  # the obstacles do shadow some of the cells


def test_cell_behind_a_wall_the_budget_cannot_cross_is_not_covered():
    r_c, n = 2.0, 2.0
    omap = wall_map([slice(40, 42)])  # a wall at x 5.0 .. 5.25
    area = CoverageArea(omap, omap.free)
    node = np.array([[4.56, 2.53]])
    unit = make_medium("unit-disk", r_c, omap).covered_mask(area, node)
    for wall_db in (3.0, 6.9, 20.0):
        covered = make_medium("multi-wall", budget(r_c, n, wall_db=wall_db), omap).covered_mask(area, node)
        rows, cols = np.nonzero(unit)
        cx = (cols + 0.5) * 0.125
        cy = (rows + 0.5) * 0.125
        d = np.hypot(cx - node[0, 0], cy - node[0, 1])
        behind = cx > 5.25
        # behind the wall a cell is heard exactly when its margin pays for the wall: d <= r_c 10^(-wall_db / 20)
        pays = 20 * np.log10(r_c / d) >= wall_db
        np.testing.assert_array_equal(covered[rows[behind], cols[behind]], pays[behind])
        assert covered[rows[~behind], cols[~behind]].all()  # this side of the wall: as the unit disk
        assert not covered[~unit].any()
    # e.g. a cell 1 m behind the node, 0.5 m beyond the wall's far face
    far = (int(2.53 / 0.125), int(5.6 / 0.125))
    assert unit[far] and not make_medium("multi-wall", budget(r_c, n, wall_db=6.9), omap).covered_mask(area, node)[far]


def test_closed_room_covers_nothing_outside_with_thick_walls():
    cells = np.zeros((60, 60), dtype=np.int8)
    cells[20:40, 20] = cells[20:40, 39] = OCCUPIED  # a room of x, y 2.625 .. 4.875 (0.125 m cells)
    cells[20, 20:40] = cells[39, 20:40] = OCCUPIED
    omap = OccupancyMap("room", 0.125, (0.0, 0.0), cells)
    area = CoverageArea(omap, omap.free)
    inside = np.zeros(omap.shape, dtype=bool)
    inside[21:39, 21:39] = True
    nodes = np.array([[3.71, 3.77], [2.93, 4.51]])
    medium = make_medium("multi-wall", budget(5.0, 2.0, wall_db=100.0), omap)
    covered = medium.covered_mask(area, nodes)
    assert covered[inside].all()  # r_c = 5 m reaches the whole room
    assert not covered[~inside].any()
    assert make_medium("unit-disk", 5.0, omap).covered_mask(area, nodes)[~inside & omap.free].sum() > 500
    # with shadowing the walls still hold: 100 dB is beyond any shadowing allowed (3 sigma = 12 dB)
    shadowed = make_medium("multi-wall", budget(5.0, 2.0, wall_db=100.0, shadowing_db=4.0), omap,
                           rng=np.random.default_rng(0)).covered_mask(area, nodes)
    assert not shadowed[~inside].any()


# -- scenarios: validation, the threshold, runs ----------------------------------------------------------------
def test_threshold_dbm_sets_r_c():
    def scenario(**radio):
        return load_scenario({"map": "obstacles-6x6", "base_stations": [{"x": 0.0, "y": 0.0}], "radio": radio})

    sc = scenario(model="log-distance", threshold_dbm=-75.0, path_loss_exponent=3.0, shadowing_db=0.0)
    want = median_range(20.0, 40.0, 3.0, -75.0)
    assert want == pytest.approx(10 ** (55 / 30))
    assert sc.radio.r_c == pytest.approx(want, rel=1e-12)
    b = sc.radio.link_budget()
    assert b.threshold_dbm == pytest.approx(-75.0, abs=1e-9) and b.r_c == sc.radio.r_c
    # the unit disk too (its RSSI uses exponent 2.5): -50 dBm is 20 - 40 - 25 log10(r_c)
    assert scenario(threshold_dbm=-50.0).radio.r_c == pytest.approx(10 ** (30 / 25), rel=1e-12)
    # other powers move the range: 10 dB more transmit power is 10^(10 / 25) times the range
    assert scenario(threshold_dbm=-50.0, tx_dbm=30.0).radio.r_c == pytest.approx(10 ** (40 / 25), rel=1e-12)
    # giving both: consistent is fine, inconsistent is refused
    assert scenario(threshold_dbm=-50.0, r_c=10 ** (30 / 25)).radio.r_c == pytest.approx(10 ** 1.2)
    with pytest.raises(ScenarioError, match=r"radio\.threshold_dbm"):
        scenario(threshold_dbm=-50.0, r_c=1.0)


def test_overrides_of_a_preset_replace_what_they_contradict():
    # a preset sets r_c; --set radio.threshold_dbm replaces it (and r_c replaces a base's threshold)
    sc = load_scenario("self-spreading-obstacles-6x6", overrides={"radio.threshold_dbm": -50.0})
    assert sc.radio.r_c == pytest.approx(10 ** (30 / 25), rel=1e-12)
    base = sc.to_dict()
    assert load_scenario(base, overrides={"radio.r_c": 2.0}).radio.threshold_dbm is None
    # both in one override: still checked against each other
    with pytest.raises(ScenarioError, match=r"radio\.threshold_dbm"):
        load_scenario("self-spreading-obstacles-6x6", overrides={"radio.threshold_dbm": -50.0, "radio.r_c": 1.0})
    # switching the model drops the base's fields the new model does not take
    walls = load_scenario("self-spreading-obstacles-6x6",
                          overrides={"radio.model": "multi-wall", "radio.wall_db": 3.4, "radio.shadowing_db": 4.0})
    assert load_scenario(walls.to_dict(), overrides={"radio.model": "unit-disk"}).radio.wall_db is None
    assert load_scenario(walls.to_dict(), overrides={"radio.model": "log-distance"}).radio.shadowing_db == 4.0
    with pytest.raises(ScenarioError, match=r"radio\.wall_db"):  # given in the same breath: refused
        load_scenario(walls.to_dict(), overrides={"radio.model": "log-distance", "radio.wall_db": 3.0})


def test_scenario_defaults_per_model():
    for model, cls, n, shadow, wall in (("unit-disk", UnitDisk, 2.5, 0.0, 0.0),
                                        ("log-distance", LogDistance, 2.5, 5.0, 0.0),
                                        ("multi-wall", MultiWall, 2.0, 0.0, 6.9)):
        b = load_scenario(PRESET, overrides={"radio.model": model}).radio.link_budget()
        assert (b.exponent, b.shadowing_db, b.wall_db) == (n, shadow, wall), model
        assert isinstance(make_medium(model, 1.0, resolve_map("open-6x6"), rng=np.random.default_rng(0)), cls)


def deployed_and_connected_check(sim: Simulation) -> tuple[np.ndarray, np.ndarray]:
    """The deployed routers, and those of them with a path to a base station through deployed nodes."""
    sw = sim.swarm
    deployed = sw.deployed
    routers = deployed & (sw.role == Role.ROUTER)
    linked = connected_to(sim.table, sim.bases, deployed)
    return np.flatnonzero(routers), np.flatnonzero(routers & ~linked)


@pytest.mark.parametrize("bases", [None, [{"x": 0.0, "y": 0.0, "region": [1.0, 1.0]},
                                         {"x": 2.0, "y": 2.0, "region": [0.6, 0.6]},
                                         {"x": -1.5, "y": 1.0, "region": [0.6, 0.6]}]],
                         ids=["one-base", "three-bases-triangles"])
def test_deployed_routers_are_connected_under_walls(bases):
    """Every router the controller has deployed (it stops only while it hears a reference) has a path to a base
    station through deployed nodes in the multi-wall table, after every step; with several bases, triangle routers
    settle too (they steer by distance to their two references)."""
    overrides = {"radio.model": "multi-wall"}
    if bases is not None:
        overrides["base_stations"] = bases
    sim = Simulation(load_scenario(PRESET, overrides=overrides), 3)
    seen, cut, triangles = 0, 0, 0
    for _ in range(800):
        sim.step()
        deployed, lost = deployed_and_connected_check(sim)
        assert len(lost) == 0, (sim.steps, lost.tolist(), sim.swarm.xy[lost].tolist(), sim.swarm.state[lost].tolist())
        seen = max(seen, len(deployed))
        cut = max(cut, len(sim.table.geometric.pairs) - len(sim.table.pairs))  # links the walls took away
        triangles = max(triangles, int((sim.swarm.state == State.TRIANGLE_SETTLED).sum()))
    assert seen >= 15 and cut >= 1  # the run deployed routers, and the walls cut links on the way
    assert (triangles >= 3) == (bases is not None)


def _run(overrides: dict, seed: int, steps: int = 120) -> Simulation:
    sim = Simulation(load_scenario(PRESET, overrides={"sim.time_limit": steps * 0.1, **overrides}), seed)
    return sim


def test_same_seed_same_run_with_shadowing_and_packet_loss():
    ov = {"radio.model": "multi-wall", "radio.shadowing_db": 5.0, "radio.packet_loss": True}
    a, b = _run(ov, 7), _run(ov, 7)
    ra, rb = a.run(), b.run()
    sa, sb = dict(ra.summary), dict(rb.summary)
    sa.pop("wall_time_s"), sb.pop("wall_time_s")
    assert sa == sb
    assert ra.timeseries_csv() == rb.timeseries_csv()
    np.testing.assert_array_equal(a.swarm.xy, b.swarm.xy)
    np.testing.assert_array_equal(a.swarm.state, b.swarm.state)
    assert a.medium.shadowing.grid.tobytes() == b.medium.shadowing.grid.tobytes()
    c = _run(ov, 8)
    assert not np.array_equal(c.medium.shadowing.grid, a.medium.shadowing.grid)


def test_radio_draws_leave_the_run_stream_alone():
    """The same seed places the robots identically under every radio (its draws come from spawned streams)."""
    plain = _run({}, 5)
    for ov in ({"radio.model": "multi-wall"}, {"radio.model": "multi-wall", "radio.shadowing_db": 5.0},
               {"radio.model": "log-distance", "radio.packet_loss": True}):
        other = _run(ov, 5)
        np.testing.assert_array_equal(other.swarm.xy, plain.swarm.xy)
        np.testing.assert_array_equal(other.swarm.heading, plain.swarm.heading)
        assert other.rng.bit_generator.state == plain.rng.bit_generator.state


# -- bad input on the command line ---------------------------------------------------------------------------
@pytest.mark.parametrize(("sets", "field"), [
    (["radio.shadowing_db=-1"], "radio.shadowing_db"),
    (["radio.model=log-distance", "radio.shadowing_db=-1"], "radio.shadowing_db"),
    (["radio.path_loss_exponent=0"], "radio.path_loss_exponent"),
    (["radio.model=nope"], "radio.model"),
    (["radio.threshold_dbm=100"], "radio.threshold_dbm"),
    (["radio.model=multi-wall", "radio.threshold_dbm=100"], "radio.threshold_dbm"),
    (["radio.model=log-distance", "radio.wall_db=3"], "radio.wall_db"),
    (["radio.wall_db=3"], "radio.wall_db"),
    (["radio.shadowing_db=2"], "radio.shadowing_db"),  # the unit disk has no shadowing
    (["radio.model=multi-wall", "sim.coverage_method=exact"], "sim.coverage_method"),
    (["radio.model=log-distance", "sim.coverage_method=exact"], "sim.coverage_method"),
])
def test_bad_radio_input_one_line_exit_2_nothing_written(tmp_path, capsys, sets, field):
    out = tmp_path / "out"
    argv = ["run", "--preset", PRESET, "--seed", "1", "--out", str(out)]
    for s in sets:
        argv += ["--set", s]
    code = main(argv)
    cap = capsys.readouterr()
    assert code == 2
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amronet: error: "), cap.err
    assert field in lines[0], lines[0]
    assert "Traceback" not in cap.err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_margins_reused_for_still_links_equal_fresh_ones():
    """A medium reuses the margins of links whose ends did not move: over a run they equal a fresh computation."""
    from amronet.engine.links import NO_PREVIOUS, candidate_margins

    sc = load_scenario("self-spreading-obstacles-6x6", overrides={"radio.model": "multi-wall",
                                                                  "radio.shadowing_db": 5.0})
    sim = Simulation(sc, 3)
    reused = 0
    for _ in range(150):
        previous = sim.medium._previous
        sim.step()
        t = sim.table.geometric
        fresh = candidate_margins(t.xy, t.indptr, t.indices, t.dist, *NO_PREVIOUS, sim.medium.hearing.plain())
        np.testing.assert_array_equal(t.link_margin, fresh)
        if previous is not None:
            reused += int(np.count_nonzero((previous[0][:, None] == t.xy[None, :]).all(-1).any(0)))
    assert reused > 0  # some nodes stood still, so the reuse was exercised
