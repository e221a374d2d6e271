"""A radio model is one extension point: one class, one registry line, one margin kernel (issue #35).

A toy model defined here gets a neighbour table, coverage and a signal map from its margin kernel alone, declares no
fast path, and says once in the log (at debug level) which slower paths it takes.
"""

from __future__ import annotations

import logging
import subprocess
import sys

import numpy as np
import pytest
from numba import njit

from amronet.engine.coverage import CoverageArea
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.radio import MEDIA, LogDistance, MultiWall, RadioMedium, UnitDisk, make_medium
from amronet.engine.walls import count_walls
from amronet.scenario import load_scenario
from amronet.sim.simulation import Simulation
from amronet.world.occupancy import OCCUPIED, OccupancyMap


@njit(cache=True)
def sight_margin(xa, ya, xb, yb, d, sa, sb, floor_db, h):
    """A toy radio: heard within 0.75 ``r_c`` in line of sight (10 dB per ``r_c``), never through a wall."""
    m = 10.0 * (0.75 * h.r_c - d) / h.r_c
    w = h.walls
    if m >= floor_db and count_walls(w.blocked, w.clear, w.ox, w.oy, w.res, xa, ya, xb, yb, 0) > 0:
        return -100.0
    return m


@pytest.fixture
def sight():
    """The toy model, registered as ``sight`` for the test only."""

    @MEDIA.register("sight")
    class Sight(RadioMedium):
        """Line of sight within three quarters of ``r_c``."""

        uses_walls = True
        link_margin = sight_margin

    yield Sight
    del MEDIA._items["sight"]


def wall_map() -> OccupancyMap:
    """A free 10 m x 5 m strip of 0.125 m cells with a wall across it at x = 5 m, with a door at the bottom."""
    cells = np.zeros((40, 80), dtype=np.int8)
    cells[8:, 40] = OCCUPIED
    return OccupancyMap("walls", 0.125, (0.0, 0.0), cells)


def margins_by_hand(medium: RadioMedium, a: np.ndarray, b: np.ndarray, floor_db: float = 0.0) -> np.ndarray:
    """The toy kernel called from Python, link by link: ``(len(a), len(b))``."""
    out = np.empty((len(a), len(b)))
    for i, (xa, ya) in enumerate(a):
        for j, (xb, yb) in enumerate(b):
            d = float(np.sqrt((xb - xa) * (xb - xa) + (yb - ya) * (yb - ya)))
            out[i, j] = sight_margin(xa, ya, xb, yb, d, 0.0, 0.0, floor_db, medium.hearing)
    return out


def test_a_toy_model_gets_a_table_coverage_and_a_signal_map(sight):
    omap = wall_map()
    medium = make_medium("sight", 2.0, omap)
    assert isinstance(medium, sight) and medium.reach == 2.0 and not medium.keeps_every_pair
    xy = np.random.default_rng(5).uniform((0.2, 0.2), (9.8, 4.8), (14, 2))

    table = medium.update(xy)  # the table: the candidates within reach whose margin is >= 0, with that margin
    indptr, indices, _ = neighbour_csr(xy, medium.reach)
    rows = np.repeat(np.arange(len(xy)), np.diff(indptr))
    by_hand = margins_by_hand(medium, xy, xy)[rows, indices]
    linked = by_hand >= 0.0
    assert 0 < linked.sum() < len(linked)  # some candidates are cut (by the wall, or beyond 0.75 r_c)
    pairs = np.stack([rows[linked], indices[linked]], axis=1)
    assert table.pairs.tolist() == pairs[pairs[:, 0] < pairs[:, 1]].tolist()
    np.testing.assert_array_equal(table.margin, by_hand[linked])
    assert table.geometric.indices.tolist() == indices.tolist()  # the bodies still see every candidate

    area = CoverageArea(omap, omap.free)  # coverage: the cells whose centre hears some node
    rr, cc = np.nonzero(area.mask)
    centres = omap.cell_centres(rr, cc)
    near = np.linalg.norm(centres[:, None] - xy[None, :4], axis=2) <= medium.reach
    expected = np.zeros(omap.shape, dtype=bool)
    expected[rr, cc] = ((margins_by_hand(medium, centres, xy[:4]) >= 0.0) & near).any(axis=1)
    for _ in range(4):  # the nodes stand still: their cells come from the medium's cache after two calls
        np.testing.assert_array_equal(medium.covered_mask(area, xy[:4]), expected)
    assert medium.coverage(area, xy[:4]) == expected.sum() / area.n_cells
    with pytest.raises(ValueError, match="raster"):
        medium.coverage(area, xy[:4], method="exact")

    signal = medium.signal_dbm(omap, xy[:2], floor_db=-20.0)  # the signal map: the best margin, every cell
    rr, cc = np.indices(omap.shape).reshape(2, -1)
    best = margins_by_hand(medium, omap.cell_centres(rr, cc), xy[:2], floor_db=-20.0)
    best[best < -20.0] = -np.inf
    want = (best.max(axis=1) + medium.budget.threshold_dbm).reshape(omap.shape)
    want[~np.isfinite(want)] = np.nan
    np.testing.assert_array_equal(signal, want)
    assert np.isnan(signal).any() and np.isfinite(signal).any()


def test_a_toy_model_says_once_which_slower_paths_it_takes(sight, caplog):
    omap = wall_map()
    xy = np.random.default_rng(1).uniform((0.2, 0.2), (9.8, 4.8), (6, 2))
    area = CoverageArea(omap, omap.free)
    with caplog.at_level(logging.DEBUG, logger="amronet.engine.radio"):
        for medium in (make_medium("sight", 2.0, omap), make_medium("sight", 2.0, omap)):
            for _ in range(3):
                medium.update(xy)
                medium.coverage(area, xy)
                medium.signal_dbm(omap, xy[:1])
    said = [r.getMessage() for r in caplog.records if r.name == "amronet.engine.radio"]
    assert len(said) == 1, said
    assert [r.levelno for r in caplog.records if r.name == "amronet.engine.radio"] == [logging.DEBUG]
    for words in ("radio model sight", "no compiled stretches", "no every_pair_is_link", "no disk_coverage",
                  "no margin_bound"):
        assert words in said[0]


def test_a_run_under_a_toy_model(sight, caplog):
    scenario = load_scenario("self-spreading-obstacles-6x6", {"radio.model": "sight", "sim.time_limit": 4.0})
    with caplog.at_level(logging.DEBUG, logger="amronet.engine.radio"):
        sim = Simulation(scenario, 1)
        assert sim.step_context().keeps_every_pair is False
        sim.run()
    assert isinstance(sim.medium, sight)
    assert 0.0 < sim.metrics().coverage <= 1.0
    assert sum(r.name == "amronet.engine.radio" for r in caplog.records) <= 1  # once per process (maybe earlier)


@pytest.mark.parametrize("quiet", [[], ["-q"]])
def test_a_multi_wall_run_says_nothing_on_stderr(quiet, tmp_path):
    """Choosing multi-wall is no mistake: its slower paths are a debug message, not a warning a user sees."""
    proc = subprocess.run([sys.executable, "-m", "amronet.cli", "run", "--preset", "self-spreading-6x6", "--out",
                           str(tmp_path / "p"), "--set", "radio.model=multi-wall", "--set", "sim.time_limit=2",
                           "--no-snapshot", *quiet], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert (proc.stdout == "") == bool(quiet)


def test_the_built_in_models_declare_their_fast_paths():
    assert UnitDisk.every_pair_is_link and UnitDisk.disk_coverage
    assert UnitDisk(1.0).keeps_every_pair
    assert not make_medium("unit-disk", 1.0, rng=np.random.default_rng(0), packet_loss=True).keeps_every_pair
    for cls in (LogDistance, MultiWall):
        assert not cls.every_pair_is_link and not cls.disk_coverage and cls.margin_bound is not None
    assert RadioMedium.margin_bound is not None


def test_a_model_with_its_own_margin_has_no_bound_unless_it_gives_one():
    class Own(RadioMedium):
        link_margin = sight_margin

    class Bounded(RadioMedium):
        link_margin = sight_margin
        margin_bound = RadioMedium.margin_bound

    assert Own.margin_bound is None and Own.link_margin is sight_margin
    assert Bounded.margin_bound is RadioMedium.margin_bound
