"""Walk rules of self-spreading (``algorithm.params.walk``): the growth field, each rule's moves, and runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

import amronet
from amronet.algorithms.self_spreading.walks import Walker
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.network import connected_to
from amronet.engine.robots import State
from amronet.engine.table import NeighbourTable
from amronet.errors import ScenarioError
from amronet.sim import Simulation

FAR = 0.3  # every beam reads its maximum range: nothing seen


def table_of(xy: np.ndarray, r: float = 1.0) -> NeighbourTable:
    indptr, indices, dist = neighbour_csr(xy, r)
    return NeighbourTable(xy=xy, r=r, indptr=indptr, indices=indices, dist=dist)


def clear_scans(m: int, beams: int = 12) -> np.ndarray:
    return np.full((m, beams), FAR)


def test_growth_field_counts_hops_to_the_newest_nodes_through_deployed_ones():
    xy = np.array([[0.0, 0.0], [0.9, 0.0], [1.8, 0.0], [2.7, 0.0], [3.6, 0.0]])
    deployed = np.array([True, True, True, True, False])
    w = Walker("growth", 5, r_c=1.0, turn_sigma=0.1, growth_s=10.0)
    field = w.growth_field(table_of(xy), deployed, t=0.0)  # everything deployed is new at first
    assert field[:4].tolist() == [0, 0, 0, 0] and field[4] == np.inf
    w.deployed_at[:3] = -100.0  # nodes 0-2 are old: node 3 alone is new
    field = w.growth_field(table_of(xy), deployed, t=0.0)
    assert field[:4].tolist() == [3, 2, 1, 0]
    w.deployed_at[3] = -100.0  # nothing new anywhere
    assert np.isinf(w.growth_field(table_of(xy), deployed, t=0.0)).all()


def chain_and_walker(rule: str, turn_sigma: float) -> tuple[np.ndarray, np.ndarray, Walker, np.ndarray]:
    """A deployed chain 0-1-2 along x (node 2 new, 0 and 1 old) and a walker, robot 3, at (0.5, 0.5)."""
    xy = np.array([[0.0, 0.0], [0.9, 0.0], [1.8, 0.0], [0.5, 0.5]])
    deployed = np.array([True, True, True, False])
    w = Walker(rule, 4, r_c=1.0, turn_sigma=turn_sigma, growth_s=10.0)
    w.deployed_at[:2] = -100.0
    return xy, deployed, w, np.zeros(4)


def steer_walker(w: Walker, heading: np.ndarray, xy: np.ndarray, deployed: np.ndarray, seed: int) -> None:
    """One step of robot 3, nothing seen, its last move not refused."""
    w.steer(heading, np.array([3]), clear_scans(1), FAR, np.zeros(1, bool), np.random.default_rng(seed),
            table_of(xy), xy, deployed, t=0.0)


def test_growth_walk_heads_down_the_field_then_outward_where_it_grows():
    # a walker that hears nodes 0 and 1 heads for node 1 (1 hop from the new node)
    xy, deployed, w, heading = chain_and_walker("growth", 0.0)
    steer_walker(w, heading, xy, deployed, 0)
    assert heading[3] == pytest.approx(math.atan2(0.0 - 0.5, 0.9 - 0.5))
    # next to the new node: outward, away from the nodes it hears
    xy[3] = [2.2, 0.1]
    steer_walker(w, heading, xy, deployed, 0)
    assert math.cos(heading[3]) > 0.9  # onward along +x


def test_guided_walk_heads_down_the_field_and_random_walks_where_the_network_grows():
    xy, deployed, w, heading = chain_and_walker("guided", 0.4)
    # it hears nodes 0 and 1 (old): down the field, to node 1, as growth does (with growth's smaller noise)
    steer_walker(w, heading, xy, deployed, 0)
    assert math.cos(heading[3] - math.atan2(-0.5, 0.4)) > 0.9
    # it hears the new node 2: the paper's random walk, heading plus the random walk's noise, same draws
    xy[3] = [2.2, 0.1]
    heading[3] = 0.3
    steer_walker(w, heading, xy, deployed, 5)
    assert heading[3] == 0.3 + 0.4 * np.random.default_rng(5).standard_normal(1)[0]
    # nothing it hears leads to growth: the random walk too
    w.deployed_at[:3] = -100.0
    heading[3] = 0.3
    steer_walker(w, heading, xy, deployed, 5)
    assert heading[3] == 0.3 + 0.4 * np.random.default_rng(5).standard_normal(1)[0]


def test_straight_walk_keeps_its_heading_while_the_way_is_clear_and_turns_off_an_obstacle():
    w = Walker("straight", 1, r_c=1.0, turn_sigma=0.3)
    heading = np.array([0.7])
    xy, deployed = np.zeros((1, 2)), np.zeros(1, bool)
    rng = np.random.default_rng(1)
    for _ in range(20):
        w.steer(heading, np.array([0]), clear_scans(1), FAR, np.zeros(1, bool), rng, table_of(xy), xy, deployed, 0.0)
    assert heading[0] == 0.7  # no noise at all
    scans = clear_scans(1)
    scans[0, 0] = 0.05  # something right ahead
    w.steer(heading, np.array([0]), scans, FAR, np.zeros(1, bool), rng, table_of(xy), xy, deployed, 0.0)
    assert math.cos(heading[0] - 0.7) < math.cos(math.pi / 4 + 1e-9)  # turned away by at least 45 degrees


def test_growth_walker_follows_the_edge_of_an_obstacle_between_it_and_its_goal():
    # it hears node 0 (+x, 1 hop from the new node 1 it does not hear) behind an obstacle seen right ahead
    xy = np.array([[3.0, 0.0], [6.0, 0.0], [0.0, 0.0]])
    deployed = np.array([True, True, False])
    w = Walker("growth", 3, r_c=5.0, turn_sigma=0.0)
    w.deployed_at[:2] = [-100.0, 0.0]
    heading = np.zeros(3)
    scans = clear_scans(1)
    scans[0, 0] = 0.05
    w.steer(heading, np.array([2]), scans, FAR, np.zeros(1, bool), np.random.default_rng(3), table_of(xy, 5.0), xy,
            deployed, t=1.0)
    assert w.follow[2] > 0
    assert abs(math.cos(heading[2])) < 0.5  # roughly along the obstacle's edge


@pytest.mark.parametrize("walk", ["straight", "growth", "guided"])
def test_every_deployed_router_stays_connected_on_a_real_map(walk):
    sc = amronet.load_scenario("self-spreading-autolab", overrides={"algorithm.params.walk": walk,
                                                                   "sim.time_limit": 60.0})
    sim = Simulation(sc, seed=2)
    for k in range(600):
        sim.step()
        if k % 20 == 0:
            deployed = sim.swarm.deployed
            assert connected_to(sim.table, sim.bases, deployed)[deployed].all(), "a deployed router is cut off"
    assert (sim.swarm.state == State.REFERENCE).sum() >= 5


def test_growth_walk_spreads_farther_than_the_random_walk_on_autolab():
    over = {"sim.time_limit": 240.0}
    random = amronet.run("self-spreading-autolab", seed=4, overrides=over).summary
    growth = amronet.run("self-spreading-autolab", seed=4,
                         overrides={**over, "algorithm.params.walk": "growth"}).summary
    assert growth["coverage"] > random["coverage"] + 0.05
    assert growth["routers_connected_fraction"] == 1.0


def test_the_demo_preset_settles_and_says_so():
    s = amronet.run("demo-autolab", seed=1).summary
    assert s["stop_reason"] == "settled" and s["routers_deployed"] == 40


def test_unknown_walk_is_a_one_line_error():
    with pytest.raises(ScenarioError) as err:
        amronet.load_scenario("self-spreading-autolab", overrides={"algorithm.params.walk": "levy"})
    assert err.value.field == "algorithm.params.walk"
    assert "\n" not in str(err.value)
