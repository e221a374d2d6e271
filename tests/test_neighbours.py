import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from amronet.engine import neighbours
from amronet.engine.neighbours import neighbour_csr, pairs_from_csr


def brute(xy: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray]:
    """Adjacency mask and squared distances, by the definition (float64, dx * dx + dy * dy <= r * r)."""
    xy = np.asarray(xy, dtype=np.float64)
    dx = xy[None, :, 0] - xy[:, None, 0]  # [i, j] = x_j - x_i
    dy = xy[None, :, 1] - xy[:, None, 1]
    d2 = dx * dx + dy * dy
    linked = d2 <= r * r
    np.fill_diagonal(linked, False)
    return linked, d2


def check_against_brute(xy: np.ndarray, r: float) -> None:
    n = len(xy)
    indptr, indices, dist = neighbour_csr(xy, r)
    assert indptr.dtype == np.int64 and indptr.shape == (n + 1,)
    assert indices.dtype in (np.int32, np.int64) and dist.dtype == np.float64
    assert indptr[0] == 0 and len(indices) == len(dist) == indptr[-1]
    linked, d2 = brute(xy, r)
    rows, cols = np.nonzero(linked)  # row-major: by row, columns ascending
    np.testing.assert_array_equal(np.diff(indptr), linked.sum(axis=1))
    np.testing.assert_array_equal(indices, cols)
    np.testing.assert_array_equal(dist, np.sqrt(d2[rows, cols]))  # bit for bit
    # symmetric (same bits both ways), rows strictly ascending, no self loops
    row_of = np.repeat(np.arange(n), np.diff(indptr))
    assert np.all(row_of != indices)
    for i in range(n):
        assert np.all(np.diff(indices[indptr[i] : indptr[i + 1]]) > 0)
    fwd = dict(zip(zip(row_of.tolist(), indices.tolist(), strict=True), dist.tolist(), strict=True))
    assert all(fwd[(j, i)] == d for (i, j), d in fwd.items())
    # the pairs i < j, by i then j
    pairs = pairs_from_csr(indptr, indices)
    assert pairs.dtype == np.int64 and pairs.shape == (len(indices) // 2, 2)
    up = rows < cols
    np.testing.assert_array_equal(pairs, np.stack([rows[up], cols[up]], axis=1).reshape(-1, 2))


@st.composite
def clouds(draw: st.DrawFn) -> tuple[np.ndarray, float]:
    n = draw(st.integers(0, 80))
    # powers of two make lattice points exactly r apart (ties); the others exercise general radii
    r = draw(st.sampled_from([1.0, 0.5, 2.0, 0.25, 4.0]) | st.floats(1e-3, 50.0))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    k = draw(st.integers(1, 4))
    centres = rng.uniform(-1.0, 1.0, (k, 2)) * draw(st.sampled_from([0.0, 1.0, 10.0, 1e3])) * r
    spread = draw(st.sampled_from([0.0, 0.3, 1.0, 3.0])) * r
    xy = centres[rng.integers(k, size=n)] + rng.normal(size=(n, 2)) * spread
    snap = rng.random(n) < draw(st.floats(0.0, 1.0))
    xy[snap] = np.round(xy[snap] / r) * r  # lattice of step r: links exactly at distance r
    dup = rng.random(n) < draw(st.floats(0.0, 0.5))
    if n:
        xy[dup] = xy[rng.integers(n, size=int(dup.sum()))]  # duplicates
    return xy, r


@settings(max_examples=300, deadline=None)
@given(clouds())
def test_matches_brute_force(cloud: tuple[np.ndarray, float]) -> None:
    xy, r = cloud
    check_against_brute(xy, r)


def test_inclusive_at_distance_r() -> None:
    indptr, indices, dist = neighbour_csr(np.array([[0.0, 0.0], [1.0, 0.0]]), 1.0)
    assert indptr.tolist() == [0, 1, 2] and indices.tolist() == [1, 0] and dist.tolist() == [1.0, 1.0]
    xy = np.array([[0.0, 0.0], [0.0, 0.5], [0.0, 1.0], [3.0, 1.0], [3.0, 2.0]])
    check_against_brute(xy, 0.5)
    assert pairs_from_csr(*neighbour_csr(xy, 0.5)[:2]).tolist() == [[0, 1], [1, 2]]


@pytest.mark.parametrize("n", [0, 1])
def test_tiny(n: int) -> None:
    indptr, indices, dist = neighbour_csr(np.zeros((n, 2)), 1.0)
    assert indptr.tolist() == [0] * (n + 1) and len(indices) == len(dist) == 0
    assert pairs_from_csr(indptr, indices).shape == (0, 2)


def test_all_identical() -> None:
    xy = np.full((30, 2), 7.25)
    indptr, _, dist = neighbour_csr(xy, 0.1)
    assert np.all(np.diff(indptr) == 29) and np.all(dist == 0.0)
    check_against_brute(xy, 0.1)


def test_large_spread() -> None:
    xy = np.array([[0.0, 0.0], [1e6, 0.0]])
    indptr, indices, _ = neighbour_csr(xy, 1.0)
    assert indptr.tolist() == [0, 0, 0] and len(indices) == 0
    xy = np.array([[0.0, 0.0], [1e6, 0.0], [1e6 + 1.0, 0.0], [0.5, 0.5], [-1e6, 3e6]])
    check_against_brute(xy, 1.0)
    # a huge box relative to r: the grid is capped and coarsened, the result must not change
    rng = np.random.default_rng(3)
    xy = rng.uniform(-1e9, 1e9, (200, 2))
    xy[100:] = xy[:100] + rng.normal(size=(100, 2))
    check_against_brute(xy, 1.0)
    xy = np.array([[1e300, 0.0], [-1e300, 0.0], [1e300, 1.0]])  # extent overflows float64
    with np.errstate(over="ignore"):
        check_against_brute(xy, 1.0)


def test_matches_kdtree_and_is_deterministic() -> None:
    rng = np.random.default_rng(0)
    n = 4000
    xy = rng.uniform(0.0, np.sqrt(n / 3.5), (n, 2))
    indptr, indices, dist = neighbour_csr(xy, 1.0)
    ref = cKDTree(xy).query_pairs(1.0, output_type="ndarray")
    ref = ref[np.lexsort((ref[:, 1], ref[:, 0]))]
    np.testing.assert_array_equal(pairs_from_csr(indptr, indices), ref)
    again = neighbour_csr(xy.copy(), 1.0)
    for a, b in zip((indptr, indices, dist), again, strict=True):
        assert a.tobytes() == b.tobytes()


@pytest.mark.parametrize("r", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_radius(r: float) -> None:
    with pytest.raises(ValueError, match="r must be"):
        neighbour_csr(np.zeros((3, 2)), r)


def test_bad_points() -> None:
    with pytest.raises(ValueError, match="non-finite"):
        neighbour_csr(np.array([[0.0, 0.0], [np.nan, 1.0]]), 1.0)
    with pytest.raises(ValueError, match="shape"):
        neighbour_csr(np.zeros((3, 3)), 1.0)


@settings(max_examples=60, deadline=None)
@given(
    sizes=st.lists(st.integers(0, 25), min_size=1, max_size=6),
    spread=st.floats(0.1, 30.0),
    r=st.floats(0.05, 5.0),
    seed=st.integers(0, 2**32 - 1),
    interleave=st.booleans(),
)
def test_groups_are_tables_of_their_own(sizes, spread, r, seed, interleave):
    """With groups, every group's rows are its own table's, bit for bit: groups on top of each other never link."""
    rng = np.random.default_rng(seed)
    parts = [rng.random((n, 2)) * spread for n in sizes]  # all groups over the same area
    xy = np.concatenate(parts)
    groups = np.repeat(np.arange(len(sizes)), sizes)
    if interleave:  # groups need not be contiguous blocks
        order = rng.permutation(len(xy))
        xy, groups = xy[order], groups[order]
    indptr, indices, dist = neighbour_csr(xy, r, groups)
    for g in range(len(sizes)):
        members = np.flatnonzero(groups == g)
        own_ptr, own_idx, own_dist = neighbour_csr(xy[members], r)
        rows = [np.arange(indptr[i], indptr[i + 1]) for i in members]
        got = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
        np.testing.assert_array_equal([len(k) for k in rows], np.diff(own_ptr))
        np.testing.assert_array_equal(indices[got], members[own_idx])
        np.testing.assert_array_equal(dist[got], own_dist)


def test_bad_groups_are_refused():
    with pytest.raises(ValueError, match="groups must be 3 integers >= 0"):
        neighbour_csr(np.zeros((3, 2)), 1.0, np.array([0, -1, 0]))
    with pytest.raises(ValueError, match="groups must be 3 integers"):
        neighbour_csr(np.zeros((3, 2)), 1.0, np.array([0, 1]))


@settings(max_examples=120, deadline=None)
@given(clouds(), st.integers(1, 3), st.integers(0, 2**32 - 1))
def test_the_threaded_table_is_the_serial_one(cloud, n_groups, seed):
    """Large searches build the rows on several threads (amronet.threads): the same table, bit for bit."""
    xy, r = cloud
    groups = np.random.default_rng(seed).integers(0, n_groups, len(xy))
    serial = neighbour_csr(xy, r, groups)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(neighbours, "use_threads", lambda n: True)
        threaded = neighbour_csr(xy, r, groups)
    for a, b in zip(serial, threaded, strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)


def test_the_threaded_search_refuses_non_finite_points(monkeypatch):
    monkeypatch.setattr(neighbours, "use_threads", lambda n: True)
    with pytest.raises(ValueError, match="non-finite"):
        neighbour_csr(np.array([[0.0, 0.0], [np.nan, 1.0]]), 1.0)
