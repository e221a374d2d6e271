"""Behavioural tests of agent-assisted router deployment: agents never lose their connection."""

import numpy as np
import pytest

from amronet.engine.network import agents_connected, connected_to
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError
from amronet.sim import Simulation
from amronet.world.space import wall_distance
from helpers import open_field_agents


def agent_scenario(**over):
    return open_field_agents(**over)


def check_every_step(sim: Simulation, steps: int) -> None:
    for _ in range(steps):
        sim.step()
        sw = sim.swarm
        network = sw.role != Role.AGENT
        assert agents_connected(sim.table, sim.agents, sim.bases, network).all(), "an agent lost its connection"
        deployed = sw.deployed
        assert connected_to(sim.table, sim.bases, deployed)[deployed].all(), "a deployed router is cut off"
        # every body keeps its radius from every wall's square (the cell-centred clearance can read a little less
        # for a body standing off its cell's centre toward a wall: the frontier explorer hugs doorways)
        assert (wall_distance(sim.world.omap, sw.xy) >= sw.radius - 1e-9).all()


@pytest.mark.parametrize(("map_name", "bases"), [
    ("open-32x32", [(2.0, 2.0)]),
    ("office-32x32", [(1.0, 1.0), (31.0, 31.0)]),
    ("cave", [(-5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)]),
])
def test_agents_never_lose_their_connection(map_name, bases):
    sc = agent_scenario(**{"map": map_name,
                           "base_stations": [{"x": x, "y": y, "region": [1.6, 1.6]} for x, y in bases]})
    if map_name == "cave":
        sc = sc.with_overrides({"radio.r_c": 2.0, "sim.dt": 0.1})
    sim = Simulation(sc, seed=3)
    check_every_step(sim, 1200)
    sw = sim.swarm
    assert (sw.state == State.REFERENCE).sum() >= 3
    assert sim.agents_connected_fraction == 1.0 and sim.agents_connected_min == 1.0
    # every released router carries a base station's status
    routers = sw.role == Role.ROUTER
    assert (sw.status[routers] >= 0).all() and set(sw.status[routers]) <= set(range(len(bases)))


def test_two_base_stations_join_by_triangles():
    sc = agent_scenario(**{"base_stations": [{"x": 2.0, "y": 16.0, "region": [1.6, 1.6]},
                                              {"x": 30.0, "y": 16.0, "region": [1.6, 1.6]}],
                           "agents.per_base": 2, "sim.time_limit": 1500.0})
    result = Simulation(sc, seed=2).run()
    states = result.summary["states"]
    assert states.get("triangle-settled", 0) + states.get("triangle", 0) >= 1
    assert result.summary["agents_connected_fraction"] == 1.0
    assert "agents_connected" in result.timeseries and (result.timeseries["agents_connected"] == 1.0).all()
    assert result.timeseries_csv().splitlines()[0].endswith(",agents_connected")


def test_run_stops_at_the_coverage_target_by_default():
    r = Simulation(agent_scenario(**{"sim.time_limit": 3000.0, "agents.per_base": 3, "radio.r_c": 8.0}),
                   seed=1).run()
    assert r.summary["coverage_target"] == 0.99
    assert r.summary["stop_reason"] == "coverage_target" and r.summary["coverage"] >= 0.99
    assert r.summary["nodes_total"] == r.summary["routers_deployed"] + 1


def test_limited_routers_tether_the_agents():
    sc = agent_scenario(**{"agents.routers_carried": 2, "sim.time_limit": 300.0})
    sim = Simulation(sc, seed=4)
    check_every_step(sim, 1200)
    assert (sim.swarm.role == Role.ROUTER).sum() <= 2 * 2
    assert sim.controller.left[sim.agents].min() >= 0


def test_released_router_is_next_to_the_agent_and_linked_to_its_reference():
    sim = Simulation(agent_scenario(), seed=5)
    while (sim.swarm.role == Role.ROUTER).sum() == 0:
        sim.step()
    sw = sim.swarm
    router = np.flatnonzero(sw.role == Role.ROUTER)[0]
    gaps = np.linalg.norm(sw.xy[sim.agents] - sw.xy[router], axis=1)
    assert gaps.min() < 0.5
    assert np.linalg.norm(sw.xy[router] - sw.xy[sim.bases[0]]) <= sim.scenario.radio.r_c


@pytest.mark.parametrize(("over", "field"), [
    ({"agents.per_base": 0}, "agents.per_base"),
    ({"routers.count": 5}, "routers.count"),
    ({"algorithm.params.explorer": "telepathy"}, "algorithm.params.explorer"),
    ({"radio.r_c": 1.0}, "algorithm.params.loss_margin"),
])
def test_bad_agent_scenarios(over, field):
    with pytest.raises(ScenarioError) as info:
        Simulation(agent_scenario(**over), 0)
    assert str(info.value).startswith(field)


def test_cached_deployed_nodes_follow_releases_and_settling():
    sim = Simulation(agent_scenario(), seed=5)
    for _ in range(400):
        sim.step()
        deployed, deployed_xy = sim.controller.deployed_nodes()
        sw = sim.swarm
        assert np.array_equal(deployed, sw.deployed) and np.array_equal(deployed_xy, sw.xy[sw.deployed])
    assert sim.controller.released >= 1
