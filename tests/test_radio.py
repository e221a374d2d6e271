import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.radio import MEDIA, UnitDisk, make_medium


def test_unit_disk_links_exactly_within_r_c():
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [2.0001, 0.0], [0.0, 0.5]])
    table = UnitDisk(1.0).update(xy)
    links = {tuple(p) for p in table.pairs.tolist()}
    assert links == {(0, 1), (0, 3)}  # (1, 3) is 1.118 m apart
    rows = np.repeat(np.arange(len(xy)), table.degree)
    assert np.allclose(table.dist, np.linalg.norm(xy[rows] - xy[table.indices], axis=1))
    assert table.degree.tolist() == [2, 1, 0, 1]
    assert (table.adjacency != table.adjacency.T).nnz == 0


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 40), st.floats(0.1, 3.0), st.integers(0, 10_000))
def test_unit_disk_matches_brute_force(n, r_c, seed):
    xy = np.random.default_rng(seed).random((n, 2)) * 5
    table = UnitDisk(r_c).update(xy)
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    expected = {(i, j) for i in range(n) for j in range(i + 1, n) if d[i, j] <= r_c}
    assert {tuple(p) for p in table.pairs.tolist()} == expected


def test_make_medium_registry():
    assert "unit-disk" in MEDIA
    assert isinstance(make_medium("unit-disk", 2.0), UnitDisk)
    try:
        make_medium("nope", 1.0)
    except ValueError as exc:
        assert "unit-disk" in str(exc)
    else:
        raise AssertionError("unknown model accepted")


def test_the_snr_at_the_threshold_is_the_root_of_the_delivery_curve():
    from scipy.optimize import brentq

    from amronet.engine import propagation as p

    root = brentq(lambda s: p._pdr_of_snr_db(s) - p.PDR_AT_THRESHOLD, 0.0, 20.0, xtol=1e-12)
    assert p.SNR_AT_THRESHOLD_DB == float(root)
    assert abs(float(p.delivery_ratio(0.0)) - p.PDR_AT_THRESHOLD) < 1e-12
