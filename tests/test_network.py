import numpy as np

from amronet.network import components, connected_to, hop_counts
from amronet.radio import UnitDisk


def chain_table():
    # 0 - 1 - 2     3 - 4   (two components)
    xy = np.array([[0, 0], [1, 0], [2, 0], [10, 0], [11, 0]], dtype=float)
    return UnitDisk(1.0).update(xy)


def test_components_and_restriction():
    t = chain_table()
    n, labels = components(t.adjacency)
    assert n == 2 and labels[0] == labels[2] != labels[3]
    nodes = np.array([True, False, True, True, True])
    n, labels = components(t.adjacency, nodes)
    assert n == 3
    assert labels[1] == -1 and labels[0] != labels[2]


def test_connected_to_sources_through_allowed_nodes():
    t = chain_table()
    assert connected_to(t.adjacency, np.array([0])).tolist() == [True, True, True, False, False]
    through = np.array([True, False, True, True, True])
    assert connected_to(t.adjacency, np.array([0]), through).tolist() == [True, False, False, False, False]


def test_hop_counts():
    t = chain_table()
    hops = hop_counts(t.adjacency, np.array([0]))
    assert hops[:3].tolist() == [0, 1, 2] and np.isinf(hops[3:]).all()
