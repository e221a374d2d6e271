"""The radio's table through a skin (amronet.engine.skin_table) is the neighbour search's table, bit for bit."""

from __future__ import annotations

import numpy as np

from amronet.engine.neighbour_search import search_kernel
from amronet.engine.skin_table import no_skin, skin_search


def _same(table, expected):
    for got, want in zip(table, expected, strict=True):
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)


def test_skin_tables_equal_the_searches_while_robots_walk_then_race():
    rng = np.random.default_rng(5)
    n = 500
    xy = rng.random((n, 2)) * 12.0
    groups = (rng.random(n) < 0.3).astype(np.int64)
    skin = no_skin()
    kept = []
    modes = []
    for step in range(60):
        xy += rng.normal(0.0, 0.02 if step < 40 else 0.6, xy.shape)  # walkers, then robots too fast for the skin
        ok, indptr, indices, dist, skin = skin_search(xy, 1.0, groups, 2, skin, True)
        expected_ok, *expected = search_kernel(xy, 1.0, groups, 2)
        assert ok and expected_ok
        _same((indptr, indices, dist), expected)
        modes.append((skin[3], skin[4]))
        kept.append(((indptr, indices, dist), [a.copy() for a in (indptr, indices, dist)]))
        if len(kept) == 2:  # the table of the call before is intact until the next call but one
            _same(*kept.pop(0))
    assert any(mode == 1 and life > 3 for mode, life in modes[:40])  # the candidates served several steps
    assert modes[-1][0] == -1  # and the skin was given up for the racers


def test_a_skin_is_not_searched_for_a_table_asked_for_once():
    xy = np.random.default_rng(1).random((50, 2)) * 3.0
    groups = np.zeros(50, dtype=np.int64)
    ok, *table, skin = skin_search(xy, 1.0, groups, 1, no_skin(), False)
    assert ok and skin[3] == 0
    _same(table, search_kernel(xy, 1.0, groups, 1)[1:])


def test_a_non_finite_position_is_reported_as_the_search_reports_it():
    xy = np.random.default_rng(2).random((50, 2)) * 3.0
    groups = np.zeros(50, dtype=np.int64)
    ok, *_, skin = skin_search(xy, 1.0, groups, 1, no_skin(), True)
    assert ok and skin[3] == 1
    xy[7, 0] = np.nan
    ok, *_ = skin_search(xy, 1.0, groups, 1, skin, True)
    assert not ok
