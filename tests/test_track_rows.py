"""Reference tracking of every robot in one state in one call: row by row what track_row gives."""

import numpy as np
import pytest

from amronet.algorithms.common.references import track_row, track_state_rows
from amronet.engine.radio import UnitDisk


@pytest.mark.parametrize("want_other", [True, False])
def test_tracking_all_rows_in_one_call_is_track_row_row_by_row(want_other):
    rng = np.random.default_rng(5)
    n = 600
    xy = rng.random((n, 2)) * 8.0
    table = UnitDisk(1.0).update(xy)
    state = rng.integers(0, 3, n)
    is_reference = rng.random(n) < 0.4
    status = rng.integers(-1, 4, n)
    current = np.where(rng.random(n) < 0.7, rng.integers(0, n, n), -1)
    current[:50] = [table.indices[table.indptr[i]] if table.indptr[i + 1] > table.indptr[i] else -1 for i in range(50)]
    out = (np.full(n, -9), np.full(n, -9), np.full(n, np.nan), np.full(n, -9))
    k = track_state_rows(state, 1, current, is_reference, status, table.indptr, table.indices, table.dist, want_other,
                         out)
    who = np.flatnonzero(state == 1)
    assert k == len(who)
    np.testing.assert_array_equal(out[0][:k], who)
    for m, i in enumerate(who):
        c, d, o, _ = track_row(i, current[i], is_reference, status, table.indptr, table.indices, table.dist,
                               want_other)
        assert (out[1][m], out[2][m], out[3][m]) == (c, d, o)
    assert (out[1][:k] != current[who]).any() and (out[3][:k] >= 0).any() == want_other
