"""What a robot hears (amronet.env.observe.heard_links) against a plain sort of its row of the neighbour table."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from amronet.engine.radio import UnitDisk
from amronet.env.observe import heard_links


def _by_sorting(table, who, relay, k):
    """The ``k`` strongest links of each robot by a stable sort: margin down, then node id up."""
    rows, mask = np.zeros((len(who), k, 4)), np.zeros((len(who), k), dtype=np.int8)
    nearest, best = np.full(len(who), np.inf), np.full(len(who), -np.inf)
    for m, i in enumerate(who):
        lo, hi = table.indptr[i], table.indptr[i + 1]
        ids, margin, dist = table.indices[lo:hi], table.margin[lo:hi], table.dist[lo:hi]
        order = np.lexsort((ids, -margin))[:k]
        rows[m, :len(order)] = np.stack([margin[order], table.threshold_dbm + margin[order], dist[order],
                                         relay[ids[order]].astype(float)], axis=1)
        mask[m, :len(order)] = 1
        if relay[ids].any():
            nearest[m], best[m] = dist[relay[ids]].min(), margin[relay[ids]].max()
    return rows, mask, nearest, best


@pytest.mark.parametrize("k", [1, 3, 8])
def test_heard_links_keeps_the_strongest_first_and_the_lower_id_on_a_tie(k):
    # robot 0 in the middle of a ring of equally distant ones (ties), and a few at random
    ring = np.array([[0.5, 0.0], [0.0, 0.5], [-0.5, 0.0], [0.0, -0.5], [0.25, 0.0], [-0.25, 0.0]])  # equal margins
    xy = np.concatenate([[[0.0, 0.0]], ring, np.random.default_rng(4).uniform(-0.7, 0.7, (12, 2))])
    table = UnitDisk(1.0).update(xy)
    relay = np.zeros(len(xy), dtype=bool)
    relay[[2, 5, 9, 11]] = True
    who = np.arange(len(xy))
    got = heard_links(table, who, relay, k)
    want = _by_sorting(table, who, relay, k)
    assert np.unique(table.margin[table.indptr[0]:table.indptr[1]]).size < table.indptr[1] - table.indptr[0]
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
