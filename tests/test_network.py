import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.network import agents_connected, component_counts, components, connected_to, hop_counts
from amronet.engine.radio import UnitDisk


def chain_table():
    # 0 - 1 - 2     3 - 4   (two components)
    xy = np.array([[0, 0], [1, 0], [2, 0], [10, 0], [11, 0]], dtype=float)
    return UnitDisk(1.0).update(xy)


def test_components_and_restriction():
    t = chain_table()
    n, labels = components(t)
    assert n == 2 and labels[0] == labels[2] != labels[3]
    nodes = np.array([True, False, True, True, True])
    n, labels = components(t, nodes)
    assert n == 3
    assert labels[1] == -1 and labels[0] != labels[2]


def test_connected_to_sources_through_allowed_nodes():
    t = chain_table()
    assert connected_to(t, np.array([0])).tolist() == [True, True, True, False, False]
    through = np.array([True, False, True, True, True])
    assert connected_to(t, np.array([0]), through).tolist() == [True, False, False, False, False]


def test_hop_counts():
    t = chain_table()
    hops = hop_counts(t, np.array([0]))
    assert hops[:3].tolist() == [0, 1, 2] and np.isinf(hops[3:]).all()
    assert hop_counts(t, np.array([0, 4]))[3] == 1


def test_agents_connected_through_the_network_only():
    # base 0 - router 1 - agent 2 ... agent 3 hears only agent 2
    xy = np.array([[0, 0], [1, 0], [2, 0], [2.9, 0]], dtype=float)
    t = UnitDisk(1.0).update(xy)
    network = np.array([True, True, False, False])
    assert agents_connected(t, np.array([2, 3]), np.array([0]), network).tolist() == [True, False]
    assert agents_connected(t, np.array([2, 3]), np.array([], dtype=np.int64), network).tolist() == [False, False]
    assert agents_connected(t, np.array([], dtype=np.int64), np.array([0]), network).tolist() == []


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 40), st.integers(0, 10_000))
def test_components_match_scipy(n, seed):
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(seed)
    t = UnitDisk(1.0).update(rng.random((n, 2)) * 4)
    nodes = rng.random(n) < 0.7
    count, labels = components(t, nodes)
    sub = t.adjacency.multiply(nodes[:, None]).multiply(nodes[None, :]).tocsr()
    sub.eliminate_zeros()
    _, ref = connected_components(sub, directed=False)
    assert count == len(np.unique(ref[nodes]))
    for i in np.flatnonzero(nodes):
        for j in np.flatnonzero(nodes):
            assert (labels[i] == labels[j]) == (ref[i] == ref[j])
    assert (labels[~nodes] == -1).all()


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 12), min_size=1, max_size=5), st.integers(0, 10_000))
def test_component_counts_per_group_are_each_blocks_count(sizes, seed):
    # several runs in one table (as a batch has them): every group gets what components gives for its block alone
    rng = np.random.default_rng(seed)
    xy = rng.random((sum(sizes), 2)) * 3
    groups = np.repeat(np.arange(len(sizes)), sizes)
    nodes = rng.random(len(xy)) < 0.7
    counts = component_counts(UnitDisk(1.0).update(xy, groups), nodes, groups, len(sizes) + 1)
    assert counts[-1] == 0
    for g in range(len(sizes)):
        mine = groups == g
        assert counts[g] == components(UnitDisk(1.0).update(xy[mine]), nodes[mine])[0]
