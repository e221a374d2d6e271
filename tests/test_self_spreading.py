"""Behavioural tests of self-spreading: the invariants the paper's algorithm promises."""

import numpy as np
import pytest

from amronet.algorithms.common.triangular import select_triangles, triangle_goal
from amronet.engine.network import connected_to
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.world.space import clearance


def check_invariants(sim: Simulation, with_metrics: bool = True) -> None:
    sw = sim.swarm
    # every deployed router has a path to a base station through deployed nodes
    deployed = sw.deployed
    linked = connected_to(sim.table, sim.bases, deployed)
    assert linked[deployed].all(), "a deployed router lost its path to the base stations"
    # nobody inside an obstacle (body clear of obstacle cells at cell granularity)
    rows, cols = sim.world.omap.world_to_cell(sw.xy)
    assert sim.world.omap.inside(sw.xy).all()
    clear = clearance(sim.world.omap)[rows, cols]
    assert (clear >= sw.radius - 1e-12).all(), "a robot overlaps an obstacle"
    if with_metrics:
        m = sim.metrics()
        assert 0.0 <= m.connected_coverage <= m.coverage <= 1.0


def run_checked(scenario, seed, steps, every=25) -> Simulation:
    sim = Simulation(scenario, seed)
    check_invariants(sim)
    for k in range(steps):
        sim.step()
        check_invariants(sim, with_metrics=k % every == 0)  # connectivity and obstacles at every step
    check_invariants(sim)
    return sim


@pytest.mark.parametrize("preset", ["self-spreading-6x6", "self-spreading-obstacles-6x6"])
def test_single_base_spreads_and_stays_connected(preset):
    sc = load_scenario(preset)
    sim = run_checked(sc, seed=1, steps=600)
    sw = sim.swarm
    refs = sw.state == State.REFERENCE
    assert refs.sum() >= 5, "routers did not deploy"
    # with one base station nobody goes into the triangle state
    assert not np.isin(sw.state, (State.TRIANGLE, State.TRIANGLE_SETTLED)).any()
    assert (sw.status[refs] == 0).all()
    # references keep their distance: each is at least (1 - margin) r_c from the nearest earlier reference
    assert sim.metrics().coverage > 0.3


def test_real_map_cave_keeps_invariants():
    sc = load_scenario({
        "map": "cave", "radio": {"r_c": 1.5},
        "base_stations": [{"x": -5.0, "y": -5.0, "region": [1.0, 1.0]}],
        "routers": {"count": 40, "robot": {"radius": 0.045, "max_speed": 0.5, "sensor_beams": 12,
                                             "sensor_range": 0.3}},
    })
    sim = run_checked(sc, seed=2, steps=400, every=40)
    assert (sim.swarm.state == State.REFERENCE).sum() >= 3


@pytest.mark.parametrize("mode", ["none", "global", "local"])
def test_two_bases_join_by_triangles(mode):
    sc = load_scenario({
        "map": "open-6x6", "radio": {"r_c": 1.0},
        "algorithm": {"params": {"triangular": mode}},
        "base_stations": [{"x": -2.0, "y": 0.0, "region": [0.8, 0.8]}, {"x": 2.0, "y": 0.0, "region": [0.8, 0.8]}],
        "routers": {"count": 40, "robot": {"radius": 0.045, "max_speed": 0.4, "sensor_beams": 12,
                                             "sensor_range": 0.14}},
    })
    sim = run_checked(sc, seed=4, steps=900, every=50)
    sw = sim.swarm
    assert set(np.unique(sw.status[sw.deployed]).tolist()) == {0, 1}
    tri = np.isin(sw.state, (State.TRIANGLE, State.TRIANGLE_SETTLED))
    assert tri.any(), "the two networks never met"
    assert sim.metrics().components < 2 + sw.deployed.sum()


def test_same_seed_same_positions_different_seed_differs():
    sc = load_scenario("self-spreading-obstacles-6x6", overrides={"sim.time_limit": 20.0})
    a = Simulation(sc, 7).run()
    b = Simulation(sc, 7).run()
    c = Simulation(sc, 8).run()
    assert a.files()["network.json"] == b.files()["network.json"]
    assert a.timeseries_csv() == b.timeseries_csv()
    assert a.files()["network.json"] != c.files()["network.json"]


def test_band_narrower_than_a_step_is_rejected():
    sc = load_scenario("self-spreading-6x6", overrides={"algorithm.params.loss_margin": 0.01})
    with pytest.raises(ScenarioError, match="loss_margin"):
        Simulation(sc, 0)


def test_triangle_goal_geometry():
    p_i = np.array([[0.0, 0.0]])
    p_j = np.array([[1.6, 0.0]])
    goal = triangle_goal(p_i, p_j, np.array([[0.8, -0.3]]), 1.0)
    assert goal[0] == pytest.approx([0.8, -0.6])
    assert np.linalg.norm(goal[0] - p_i[0]) == pytest.approx(1.0)
    assert np.linalg.norm(goal[0] - p_j[0]) == pytest.approx(1.0)
    far = triangle_goal(p_i, np.array([[3.0, 0.0]]), np.array([[1.0, 1.0]]), 1.0)
    assert far[0] == pytest.approx([1.5, 0.0])


def test_select_triangles_rules():
    from amronet.engine.radio import UnitDisk

    xy = np.array([[0, 0], [1.6, 0], [0.8, 0.5], [0.8, -0.5], [5, 5], [5.5, 5]], dtype=float)
    table = UnitDisk(1.0).update(xy)
    disabled = np.zeros(6, dtype=bool)
    committed = np.array([True, True, False, False, True, True])
    deciders, ri, rj = np.array([2, 3]), np.array([0, 0]), np.array([1, 1])
    # two robots meet the same pair in the same step: only one (the lower id) deploys
    assert select_triangles("none", deciders, ri, rj, xy, 1.0, disabled, table, committed).tolist() == [
        True, False]
    disabled[[0, 1]] = True
    assert not select_triangles("local", deciders, ri, rj, xy, 1.0, disabled, table, committed).any()
    # references within r_c of each other are linked already: never a triangle
    assert not select_triangles("none", np.array([2]), np.array([4]), np.array([5]), xy, 1.0, disabled,
                                table, committed).any()
    # global: 0 and 1 are not connected through committed nodes -> deploy; once joined -> skip
    assert select_triangles("global", deciders[:1], ri[:1], rj[:1], xy, 1.0, disabled, table,
                            committed).tolist() == [True]
    committed[2] = True
    assert not select_triangles("global", deciders[:1], ri[:1], rj[:1], xy, 1.0, disabled, table,
                                committed).any()


def test_routers_start_near_their_base_with_status_minus_one():
    sim = Simulation(load_scenario("self-spreading-6x6"), 0)
    sw = sim.swarm
    routers = sw.role == Role.ROUTER
    assert (sw.status[routers] == -1).all() and (sw.state[routers] == State.EXPLORE).all()
    assert (np.abs(sw.xy[routers]) <= 0.5 + 1e-9).all()
    assert (np.linalg.norm(sw.xy[routers], axis=1) <= 0.95).all()


def test_stop_conditions_terminated_vs_truncated():
    sc = load_scenario("self-spreading-6x6", overrides={"sim.time_limit": 30.0})
    r = Simulation(sc, 1).run()
    assert r.summary["stop_reason"] == "time_limit" and not r.summary["terminated"] and r.summary["truncated"]
    assert r.summary["sim_time_s"] == 30.0 and r.summary["steps"] == 300
    r = Simulation(sc.with_overrides({"sim.coverage_target": 0.3}), 1).run()
    assert r.summary["stop_reason"] == "coverage_target" and r.summary["terminated"]
    assert r.summary["coverage"] >= 0.3 and r.summary["sim_time_s"] < 30.0
    few = sc.with_overrides({"routers.count": 3, "sim.time_limit": 600.0})
    r = Simulation(few, 1).run()
    assert r.summary["stop_reason"] == "settled" and r.summary["terminated"]
    assert r.summary["routers_deployed"] == 3


def test_shared_floor_plan_from_its_own_folder(shared_maps):
    sc = load_scenario({
        "map": str(shared_maps / "hospital_section.yaml"), "radio": {"r_c": 2.0},
        "base_stations": [{"x": 19.0, "y": 8.0, "region": [1.0, 1.0]}],
        "routers": {"count": 40, "robot": {"radius": 0.045, "max_speed": 0.5, "sensor_beams": 12,
                                             "sensor_range": 0.3}},
    })
    sim = run_checked(sc, seed=5, steps=400, every=40)
    assert sim.world.omap.name == "hospital_section"
    assert (sim.swarm.state == State.REFERENCE).sum() >= 3
