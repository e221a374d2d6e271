"""The optimum on tiny maps whose answer is known by hand, checked by amronet's own coverage and connectivity code."""

import itertools
import math

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from amronet.engine.coverage import CoverageArea
from amronet.engine.network import connected_to
from amronet.errors import AmronetError
from amronet.optimum import build_instance, find_optimum
from amronet.optimum.heuristic import connected, covers_all
from amronet.optimum.reduce import reduce_instance
from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap

RES = 0.05


def corridor(columns: int, rows: int = 10) -> OccupancyMap:
    """A straight corridor: ``columns`` free cells long, ``rows`` free cells wide (0.05 m cells), walled around."""
    cells = np.full((rows + 2, columns + 2), OCCUPIED, dtype=np.int8)
    cells[1:-1, 1:-1] = FREE
    return OccupancyMap("corridor", RES, (0.0, 0.0), cells)


def room(side_cells: int) -> OccupancyMap:
    cells = np.full((side_cells + 2, side_cells + 2), OCCUPIED, dtype=np.int8)
    cells[1:-1, 1:-1] = FREE
    return OccupancyMap("room", RES, (0.0, 0.0), cells)


def amronet_checks(opt) -> tuple[float, bool]:
    """Coverage of the reachable space and connectivity of the placement, by the engine's code (not the solver's)."""
    inst = opt.instance
    xy = np.vstack([inst.bases_xy, opt.routers])
    covered = inst.medium.covered_mask(CoverageArea(inst.omap, inst.reachable), xy)
    table = inst.medium.update(xy)
    linked = connected_to(table, np.arange(len(inst.bases_xy)))
    return float(covered[inst.reachable].mean()), bool(linked.all())


def chain_needed(columns: int, base_x: float, r: float, half_width: float) -> int:
    """Routers a straight corridor needs beyond its base station: a chain r apart whose last covers the far corners."""
    far = (columns - 0.5) * RES + RES  # centre of the last free column
    return max(0, math.ceil((far - base_x - math.sqrt(r * r - half_width**2)) / r - 1e-9))


@pytest.mark.parametrize("columns", [60, 75, 98, 140])
def test_a_corridor_needs_a_chain_of_routers_r_c_apart(columns):
    omap = corridor(columns)
    opt = find_optimum(omap, [(0.3, 0.3)], r_c=1.0, spacing=0.25, time_limit=20)
    expected = chain_needed(columns, 0.3, 1.0, 0.225)  # cell centres lie up to 0.225 m off the corridor's axis
    assert opt.count == expected
    assert opt.optimal and opt.lower == expected
    assert amronet_checks(opt) == (1.0, True)
    assert opt.verified == {"coverage": 1.0, "connected": True, "uncovered_cells": 0}


def test_coverage_alone_needs_two_but_connectivity_three():
    opt = find_optimum(corridor(75), [(0.3, 0.3)], r_c=1.0, spacing=0.25, time_limit=20)
    assert opt.bounds["set_cover"] == {"lower": 2, "status": "optimal", "value": 2}
    assert opt.count == 3 and opt.optimal
    assert amronet_checks(opt) == (1.0, True)


def test_one_router_in_the_middle_covers_an_open_room():
    opt = find_optimum(room(60), [(0.4, 0.4)], r_c=2.5, spacing=0.5, time_limit=20)  # 3 m x 3 m
    assert (opt.count, opt.lower, opt.optimal) == (1, 1, True)
    assert amronet_checks(opt) == (1.0, True)


def test_the_base_alone_covers_a_small_room():
    opt = find_optimum(room(40), [(1.0, 1.0)], r_c=2.0, spacing=0.5, time_limit=5)
    assert (opt.count, opt.lower, opt.optimal, opt.gap) == (0, 0, True, 0.0)


@pytest.mark.parametrize("spacing", [0.5, 50.0])
def test_the_base_alone_needs_no_site_whatever_the_spacing(spacing):
    """On a lattice too coarse for any site the answer is still 0 routers when the base covers everything."""
    opt = find_optimum(room(40), [(1.0, 1.0)], r_c=50.0, spacing=spacing, time_limit=5)
    assert (opt.count, opt.lower, opt.optimal, opt.gap) == (0, 0, True, 0.0)
    assert opt.verified == {"coverage": 1.0, "connected": True, "uncovered_cells": 0}
    assert (opt.instance.n_sites == 0) == (spacing == 50.0)
    with pytest.raises(AmronetError, match="no candidate site of the 50 m lattice lies where a router fits"):
        build_instance(room(40), [(1.0, 1.0)], r_c=0.5, spacing=50.0)  # cells the base leaves need a site


def test_walls_stop_the_multi_wall_radio_so_each_room_needs_its_router():
    cells = np.full((42, 122), OCCUPIED, dtype=np.int8)  # three 2 m rooms in a row, 6 m long, doors 0.5 m wide
    cells[1:-1, 1:-1] = FREE
    for c in (41, 81):
        cells[1:-1, c] = OCCUPIED
        cells[15:25, c] = FREE
    omap = OccupancyMap("rooms", RES, (0.0, 0.0), cells)
    disk = find_optimum(omap, [(0.5, 1.0)], r_c=3.0, spacing=0.5, time_limit=20)
    walls = find_optimum(omap, [(0.5, 1.0)], r_c=3.0, spacing=0.5, radio={"model": "multi-wall", "wall_db": 30.0},
                         time_limit=20)
    assert disk.optimal and walls.optimal
    assert walls.count > disk.count
    assert amronet_checks(walls) == (1.0, True) and amronet_checks(disk) == (1.0, True)


def brute_force(inst) -> int:
    """The fewest instance sites that cover every sample cell and connect, by enumeration (tiny instances only)."""
    n = inst.n_sites
    rows = np.unique(inst.cover.toarray().astype(bool), axis=0)  # cells covered by the same sites: one row
    for size in range(0, n + 1):
        for combo in itertools.combinations(range(n), size):
            if not rows[:, list(combo)].any(axis=1).all():
                continue
            chosen = np.zeros(n, dtype=bool)
            chosen[list(combo)] = True
            if connected(inst.links, inst.base_linked, chosen):
                return size
    raise AssertionError("no placement at all")


@st.composite
def small_maps(draw):
    rows, cols = draw(st.integers(18, 30)), draw(st.integers(18, 30))
    cells = np.full((rows, cols), OCCUPIED, dtype=np.int8)
    cells[1:-1, 1:-1] = FREE
    for _ in range(draw(st.integers(0, 3))):  # walls with a gap
        if draw(st.booleans()):
            c = draw(st.integers(7, cols - 8))
            gap = draw(st.integers(2, rows - 7))
            cells[1:-1, c] = OCCUPIED
            cells[gap:gap + 5, c] = FREE
        else:
            r = draw(st.integers(7, rows - 8))
            gap = draw(st.integers(2, cols - 7))
            cells[r, 1:-1] = OCCUPIED
            cells[r, gap:gap + 5] = FREE
    r_c = draw(st.sampled_from([0.8, 1.0, 1.2]))
    radio = draw(st.sampled_from([None, {"model": "multi-wall", "wall_db": 3.0}]))
    return OccupancyMap("random", 0.1, (0.0, 0.0), cells), r_c, radio


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_maps())
def test_bound_never_exceeds_the_best_and_the_best_is_the_true_optimum(case):
    omap, r_c, radio = case
    try:
        opt = find_optimum(omap, [(0.35, 0.35)], r_c=r_c, spacing=0.4, radio=radio, time_limit=5)
    except Exception as exc:  # a lattice that cannot cover the map is refused, one line naming --spacing
        assert str(exc).startswith("--spacing:"), exc
        return
    assert opt.lower <= opt.count
    assert amronet_checks(opt) == (1.0, True)
    inst = opt.instance
    if inst.n_sites <= 32 and opt.count <= 4:
        assert opt.optimal and opt.count == brute_force(inst)


def test_reductions_keep_the_optimum():
    inst = build_instance(corridor(98), [(0.3, 0.3)], 1.0, 0.25)
    red = reduce_instance(inst)
    assert red.stats["minimal_rows"] <= red.stats["distinct_rows"] <= red.stats["cells"]
    assert red.stats["dominated_sites"] > 0  # sites by the walls cover and link less than their neighbours
    every = np.ones(red.n, dtype=bool)
    assert covers_all(red.rows, every) and connected(red.links, red.base_linked, every)
    # each kept row is one of the instance's cells' sets, restricted to the kept sites
    cells = sp.csr_matrix(inst.cover[:, red.keep])
    sets = {tuple(cells.indices[cells.indptr[i]:cells.indptr[i + 1]]) for i in range(cells.shape[0])}
    assert all(tuple(red.rows.indices[red.rows.indptr[i]:red.rows.indptr[i + 1]]) in sets
               for i in range(red.rows.shape[0]))


def test_coarse_to_fine_starts_from_the_lattice_of_twice_the_spacing():
    opt = find_optimum(corridor(140), [(0.3, 0.3)], r_c=1.0, spacing=0.25, time_limit=20, coarse=True)
    assert opt.coarse["used"] and opt.coarse["spacing_m"] == 0.5
    assert opt.count <= opt.coarse["start_routers"] <= opt.coarse["routers"]  # the coarse placement holds on the fine
    assert opt.optimal and amronet_checks(opt) == (1.0, True)
