"""Tests of amronet.world.space: reachable free space and clearance."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from amronet.errors import MapError
from amronet.world import FREE, OCCUPIED, UNKNOWN, OccupancyMap, clearance, reachable_free


def make_map(
    cells: np.ndarray, resolution: float = 0.1, origin: tuple[float, float] = (0.0, 0.0)
) -> OccupancyMap:
    return OccupancyMap(
        name="test", resolution=resolution, origin=origin, cells=np.asarray(cells, dtype=np.int8)
    )


def ring_map() -> OccupancyMap:
    """20 x 20 free cells (no border, so the map's outside is 'free' too) with a square ring wall 5..14."""
    cells = np.zeros((20, 20), dtype=np.int8)
    cells[5:15, 5:15] = OCCUPIED
    cells[6:14, 6:14] = FREE
    return make_map(cells)


# --- reachable_free ---------------------------------------------------------------------------------------


def test_inside_the_ring_only_the_inside_is_reachable() -> None:
    omap = ring_map()
    reach = reachable_free(omap, np.array([1.0, 1.0]))
    assert reach.shape == omap.shape
    assert reach.sum() == 8 * 8
    assert reach[6:14, 6:14].all()


@settings(max_examples=60, deadline=None)
@given(arrays(np.int8, (12, 15), elements=st.sampled_from([FREE, FREE, OCCUPIED])), st.integers(0, 2**32 - 1))
def test_reachable_free_is_the_components_of_the_seeds(cells, seed) -> None:
    from scipy import ndimage

    omap = make_map(cells)
    free = np.argwhere(omap.free)
    rng = np.random.default_rng(seed)
    pick = free[rng.integers(0, len(free), min(len(free), int(rng.integers(0, 4))))] if len(free) else free
    seeds = (pick[:, ::-1] + 0.5) * omap.resolution
    labels, _ = ndimage.label(omap.free, structure=ndimage.generate_binary_structure(2, 1))
    expected = np.isin(labels, np.unique(labels[pick[:, 0], pick[:, 1]])) if len(pick) else ~omap.free & omap.free
    for _ in range(2):  # the components are computed once per map and kept: the second call reads them
        np.testing.assert_array_equal(reachable_free(omap, seeds), expected)


def test_outside_the_ring_does_not_leak_inside_nor_off_the_map() -> None:
    omap = ring_map()
    reach = reachable_free(omap, np.array([[0.05, 0.05]]))
    assert reach.sum() == 20 * 20 - 10 * 10
    assert not reach[6:14, 6:14].any()


def test_several_seeds_give_the_union() -> None:
    omap = ring_map()
    reach = reachable_free(omap, np.array([[0.05, 0.05], [1.0, 1.0], [1.05, 1.05]]))
    assert reach.sum() == 20 * 20 - 10 * 10 + 8 * 8
    assert not (reach & ~omap.free).any()


def test_one_pixel_diagonal_wall_blocks_the_flood_fill() -> None:
    cells = np.zeros((10, 10), dtype=np.int8)
    cells[np.arange(10), np.arange(10)] = OCCUPIED  # cells touch only at corners
    omap = make_map(cells)
    reach = reachable_free(omap, np.array([0.85, 0.15]))  # below the diagonal (row 1, col 8)
    rows, cols = np.indices(cells.shape)
    np.testing.assert_array_equal(reach, rows < cols)


def test_unknown_cells_block() -> None:
    cells = np.zeros((3, 5), dtype=np.int8)
    cells[:, 2] = UNKNOWN
    reach = reachable_free(make_map(cells), np.array([0.05, 0.05]))
    assert reach.sum() == 6
    assert not reach[:, 3:].any()


def test_origin_is_respected() -> None:
    omap = make_map(ring_map().cells, origin=(-1.0, -1.0))
    assert reachable_free(omap, np.array([0.0, 0.0])).sum() == 64


def test_seed_in_a_wall_raises_naming_it() -> None:
    omap = ring_map()
    with pytest.raises(MapError) as exc:
        reachable_free(omap, np.array([[0.05, 0.05], [0.55, 0.55]]))
    assert exc.value.field == "seeds[1]"
    assert "(0.55, 0.55)" in str(exc.value)
    assert "\n" not in str(exc.value)


def test_seed_off_the_map_raises() -> None:
    with pytest.raises(MapError) as exc:
        reachable_free(ring_map(), np.array([-0.5, 1.0]))
    assert exc.value.field == "seeds[0]"
    assert "outside" in str(exc.value)


def test_no_seed_reaches_nothing() -> None:
    assert not reachable_free(ring_map(), np.zeros((0, 2))).any()


# --- clearance --------------------------------------------------------------------------------------------


def test_clearance_next_to_a_wall() -> None:
    cells = np.zeros((9, 12), dtype=np.int8)
    cells[:, 0] = OCCUPIED
    omap = make_map(cells, resolution=0.1)
    clear = clearance(omap)
    assert clear.shape == omap.shape
    assert (clear[:, 0] == 0).all()
    # middle row: the wall on the left (col 0) is nearer than the map's edges for cols 1..3
    assert clear[4, 1] == pytest.approx(0.05)
    assert clear[4, 2] == pytest.approx(0.15)
    assert clear[4, 3] == pytest.approx(0.25)
    # the map's edge counts as a wall: the top and bottom rows are 0.5 cell from it
    assert clear[0, 6] == pytest.approx(0.05)
    assert clear[8, 6] == pytest.approx(0.05)
    assert clear[4, 6] == pytest.approx(0.45)  # 4 cells from the top and bottom edges


def test_clearance_of_unknown_and_diagonal() -> None:
    cells = np.zeros((11, 11), dtype=np.int8)
    cells[5, 5] = UNKNOWN
    omap = make_map(cells, resolution=1.0)
    clear = clearance(omap)
    assert clear[5, 5] == 0
    assert clear[5, 6] == pytest.approx(0.5)
    assert clear[6, 6] == pytest.approx(np.sqrt(2) - 0.5)
    assert clear[5, 8] == pytest.approx(2.5)


def test_clearance_is_cached_and_read_only() -> None:
    omap = ring_map()
    first = clearance(omap)
    assert clearance(omap) is first
    assert omap._cache["clearance"] is first
    assert not first.flags.writeable


def brute_force_clearance(cells: np.ndarray, res: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre-to-centre convention and exact distance to the nearest blocked square, padding the outside."""
    padded = np.pad(cells != FREE, 1, constant_values=True)
    br, bc = np.nonzero(padded)
    rows, cols = np.indices(cells.shape)
    dr = (rows[..., None] + 1 - br) * res
    dc = (cols[..., None] + 1 - bc) * res
    centre = np.sqrt(dr**2 + dc**2).min(axis=-1)
    gap_r = np.clip(np.abs(dr) - res / 2, 0, None)
    gap_c = np.clip(np.abs(dc) - res / 2, 0, None)
    exact = np.sqrt(gap_r**2 + gap_c**2).min(axis=-1)
    return np.clip(centre - res / 2, 0, None), exact


@settings(max_examples=30, deadline=None)
@given(
    arrays(
        np.int8, st.tuples(st.integers(1, 9), st.integers(1, 9)), elements=st.sampled_from([0, 0, 0, 1, -1])
    )
)
def test_clearance_matches_brute_force(cells: np.ndarray) -> None:
    res = 0.05
    clear = clearance(make_map(cells, resolution=res))
    convention, exact = brute_force_clearance(cells, res)
    np.testing.assert_allclose(clear, convention, atol=1e-12)
    # the convention never underestimates the true distance and overestimates it by at most 0.21 cells
    assert (clear >= exact - 1e-12).all()
    assert (clear <= exact + (np.sqrt(2) - 1) / 2 * res + 1e-12).all()
    assert (clear[cells != FREE] == 0).all()
