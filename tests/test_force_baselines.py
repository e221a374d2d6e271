"""Force-based baselines: the force helpers, DSSA and the potential field (Poduri & Sukhatme, Howard et al.)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.algorithms.common.forces import clamp_norm, links_of, obstacle_hits, sum_per_node
from amronet.algorithms.dssa.controller import DSSA
from amronet.algorithms.potential_field.controller import PotentialField
from amronet.engine.radio import UnitDisk
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.world.space import clearance


def scenario(algorithm, params=None, count=30, map_name="open-6x6", region=(1.0, 1.0), time_limit=300.0,
             base=(0.0, 0.0)):
    return load_scenario({
        "name": "t", "map": map_name, "algorithm": {"name": algorithm, "params": params or {}},
        "radio": {"model": "unit-disk", "r_c": 1.0},
        "base_stations": [{"x": base[0], "y": base[1], "region": list(region)}],
        "routers": {"count": count, "robot": "bebot"},
        "sim": {"dt": 0.1, "time_limit": time_limit, "record_every": 10},
    })


# -- helpers ----------------------------------------------------------------------------------------------------
@settings(max_examples=40, deadline=None)
@given(st.integers(2, 30), st.integers(0, 2**31 - 1))
def test_link_forces_of_a_symmetric_law_cancel(n, seed):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 2, size=(n, 2))
    table = UnitDisk(1.0).update(xy)
    links = links_of(table, xy, np.arange(n))
    assert len(links.row) == 2 * len(table.pairs)
    np.testing.assert_allclose(np.hypot(*links.away.T), 1.0)
    np.testing.assert_allclose(xy[links.row] - xy[links.col], links.away * links.dist[:, None], atol=1e-12)
    # any central pairwise law (here 1 / d) is Newton's third law: the forces sum to zero
    total = sum_per_node(links.row, links.away / links.dist[:, None], n).sum(axis=0)
    np.testing.assert_allclose(total, 0.0, atol=1e-9)


def test_links_of_a_subset_and_coincident_points():
    xy = np.array([[0.0, 0.0], [0.0, 0.0], [0.5, 0.0], [3.0, 3.0]])
    table = UnitDisk(1.0).update(xy)
    links = links_of(table, xy, np.array([0, 1]))
    assert set(links.row) == {0, 1}
    coincident = (links.row == 0) & (links.col == 1)
    opposite = (links.row == 1) & (links.col == 0)
    np.testing.assert_allclose(links.away[coincident], -links.away[opposite])  # pushed apart, opposite ways
    assert (links.dist > 0).all()


def test_obstacle_hits_point_away_from_what_the_beams_see():
    scans = np.full((2, 4), 0.14)
    scans[0, 0] = 0.05  # robot 0, heading 0: the forward beam sees a wall 5 cm ahead (+x)
    scans[1, 1] = 0.10  # robot 1, heading pi/2: beam 1 (90 deg left of forward) looks along -x
    hits = obstacle_hits(scans, np.array([0.0, np.pi / 2]), 0.14)
    assert list(hits.row) == [0, 1]
    np.testing.assert_allclose(hits.away[0], [-1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(hits.away[1], [1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(hits.dist, [0.05, 0.10])


def test_clamp_norm():
    v = np.array([[3.0, 4.0], [0.1, 0.0], [0.0, 0.0]])
    out = clamp_norm(v, 1.0)
    np.testing.assert_allclose(out, [[0.6, 0.8], [0.1, 0.0], [0.0, 0.0]])


# -- DSSA -------------------------------------------------------------------------------------------------------
def no_robot_in_an_obstacle(sim):
    rows, cols = sim.world.omap.world_to_cell(sim.swarm.xy)
    assert (clearance(sim.world.omap)[rows, cols] >= sim.swarm.radius - 1e-12).all()


@pytest.mark.parametrize("map_name", ["open-6x6", "obstacles-6x6"])
def test_dssa_spreads_and_converges_by_its_stop_rules(map_name):
    sim = Simulation(scenario("dssa", map_name=map_name), seed=3)
    start = sim.metrics().coverage
    result = sim.run()
    no_robot_in_an_obstacle(sim)
    s = result.summary
    assert s["stop_reason"] == "settled" and s["settled_at_s"] is not None and s["settled_at_s"] < 100
    assert s["coverage"] > start + 0.4
    assert s["stopped_by_oscillation"] + s["stopped_by_stability"] == 30
    assert (sim.swarm.state[sim.swarm.role == Role.ROUTER] == State.REFERENCE).all()
    # every move was limited by the robots' maximum speed
    assert (sim.swarm.distance <= sim.swarm.max_speed * s["sim_time_s"] + 1e-9).all()


def test_dssa_expected_density_uses_the_virtual_sensing_radius():
    sim = Simulation(scenario("dssa", params={"field_area": 36.0}), seed=0)
    assert sim.controller.mu == pytest.approx(31 * np.pi * 0.5**2 / 36.0)
    sim = Simulation(scenario("dssa", params={"field_area": 36.0, "sensing_radius_factor": 1.0}), seed=0)
    assert sim.controller.mu == pytest.approx(31 * np.pi / 36.0)


def test_dssa_isolated_router_stops_by_the_stability_rule():
    # one router far from everybody feels no force, stands still and stops after stable_steps steps
    sc = scenario("dssa", params={"stable_steps": 7}, count=1, region=(0.6, 0.6), base=(2.0, 2.0))
    sim = Simulation(sc, seed=0)
    router = np.flatnonzero(sim.swarm.role == Role.ROUTER)[0]
    sim.swarm.xy[router] = (-2.0, -2.0)
    sim.table = sim.medium.update(sim.swarm.xy)
    for _ in range(6):
        sim.step()
    assert sim.swarm.state[router] == State.EXPLORE
    sim.step()
    assert sim.swarm.state[router] == State.REFERENCE
    assert sim.controller.stopped_by["stability"] == 1


def test_dssa_oscillating_router_stops_at_the_centre_of_its_oscillation():
    sc = scenario("dssa", params={"oscillation_limit": 3}, count=1, region=(0.6, 0.6), base=(2.0, 2.0))
    sim = Simulation(sc, seed=0)
    ctl: DSSA = sim.controller
    sw = sim.swarm
    r = np.flatnonzero(sw.role == Role.ROUTER)
    sw.xy[r] = (0.0, 0.0)
    ctl.anchor[r] = sw.xy[r]
    ctl.visit_sum[r] = sw.xy[r]
    # drive it back and forth by hand: +x, -x, +x, -x (three reversals)
    for k, dx in enumerate((0.01, -0.01, 0.01, -0.01)):
        ctl.before[r] = sw.xy[r]
        if k > 0:
            ctl.reversals[r] += 1  # what decide() counts when the new step reverses the last one
        sw.xy[r] += (dx, 0.0)
        ctl.after_move(r, np.zeros(1, dtype=bool))
    assert ctl.finishing[r].all()
    np.testing.assert_allclose(ctl.goal[r][0], [0.004, 0.0], atol=1e-12)  # mean of 0, .01, 0, .01, 0
    assert ctl.stopped_by["oscillation"] == 1


def test_dssa_rejects_bad_parameters():
    with pytest.raises(ScenarioError, match="oscillation_limit"):
        scenario("dssa", params={"oscillation_limit": 0})
    with pytest.raises(ScenarioError, match="bogus"):
        scenario("dssa", params={"bogus": 1})


# -- potential field --------------------------------------------------------------------------------------------
def test_constrained_coverage_router_settles_at_the_balance_distance():
    # K = 1: a lone router hears only the base node; its link is critical, so cover and degree forces balance at
    # d* = balance_fraction * Q * r_c = 0.75 * 0.8 * 1 = 0.6 m
    sc = scenario("potential-field", params={"obstacle_forces": False}, count=1, region=(0.3, 0.3))
    sim = Simulation(sc, seed=2)
    result = sim.run()
    assert result.summary["stop_reason"] == "settled"
    router = np.flatnonzero(sim.swarm.role == Role.ROUTER)[0]
    d = np.hypot(*(sim.swarm.xy[router] - sim.swarm.xy[sim.bases[0]]))
    assert d == pytest.approx(0.6, abs=0.03)
    assert result.summary["routers_connected_fraction"] == 1.0


def test_constants_follow_the_documented_derivation():
    sim = Simulation(scenario("potential-field"), seed=0)
    ctl: PotentialField = sim.controller
    assert ctl.k_cover == pytest.approx(0.25 * 0.2 * 0.5**2)
    d_star, q_rc = 0.6, 0.8
    assert ctl.k_cover / d_star**2 == pytest.approx(ctl.k_degree / (q_rc - d_star) ** 2)


def test_howard_field_pushes_a_router_out_of_range():
    # K = 0 (Howard et al.): only repulsion, so the router leaves the base's range and coasts to rest
    sc = scenario("potential-field", params={"connectivity_k": 0, "obstacle_forces": False}, count=1,
                  region=(0.3, 0.3))
    sim = Simulation(sc, seed=2)
    result = sim.run()
    router = np.flatnonzero(sim.swarm.role == Role.ROUTER)[0]
    assert np.hypot(*(sim.swarm.xy[router] - sim.swarm.xy[sim.bases[0]])) > 1.0
    assert result.summary["routers_connected_fraction"] == 0.0


def test_obstacle_forces_push_a_router_off_a_wall():
    # a router parked 8 cm from the west wall of the field, far from the base, heading into the wall
    def final_x(obstacle_forces):
        sc = scenario("potential-field", params={"connectivity_k": 0, "obstacle_forces": obstacle_forces},
                      count=1, region=(0.6, 0.6), base=(2.0, 2.0), time_limit=5.0)
        sim = Simulation(sc, seed=0)
        r = np.flatnonzero(sim.swarm.role == Role.ROUTER)[0]
        x_wall = sim.world.omap.extent[0]
        sim.swarm.xy[r] = (x_wall + 0.13, -2.0)
        sim.swarm.heading[r] = np.pi
        sim.table = sim.medium.update(sim.swarm.xy)
        sim.run()
        return sim.swarm.xy[r, 0] - x_wall

    assert final_x(True) > 0.2
    assert final_x(False) == pytest.approx(0.13)


@pytest.mark.parametrize("algorithm", ["dssa", "potential-field"])
def test_same_seed_same_run(algorithm):
    a = Simulation(scenario(algorithm, map_name="obstacles-6x6", time_limit=20.0), seed=5).run()
    b = Simulation(scenario(algorithm, map_name="obstacles-6x6", time_limit=20.0), seed=5).run()
    np.testing.assert_array_equal(a.run.swarm.xy, b.run.swarm.xy)
    np.testing.assert_array_equal(a.timeseries["coverage"], b.timeseries["coverage"])


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 25), st.integers(0, 2), st.integers(0, 2**31 - 1))
def test_compiled_constrained_coverage_matches_the_link_formula(n, k_conn, seed):
    from amronet.algorithms.common.forces import constrained_coverage_forces

    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 1.5, size=(n, 2))
    table = UnitDisk(1.0).update(xy)
    who = np.sort(rng.choice(n, size=max(1, n // 2), replace=False))
    k_cover, k_degree, q_rc, cap = 0.0125, 0.0014, 0.8, 0.2
    links = links_of(table, xy, who)
    mag = np.minimum(k_cover / links.dist**2, cap)
    critical = np.diff(table.indptr)[links.row] <= k_conn
    slack = q_rc - links.dist
    pull = np.where(slack > 0, np.minimum(k_degree / np.maximum(slack, 1e-12) ** 2, cap), cap)
    mag = mag - np.where(critical, pull, 0.0)
    expected = sum_per_node(links.row, links.away * mag[:, None], n)[who]
    got = constrained_coverage_forces(table, xy, who, k_cover, k_degree, q_rc, cap, k_conn)
    np.testing.assert_allclose(got, expected, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 8), st.integers(0, 2**31 - 1))
def test_compiled_obstacle_forces_match_the_hits(m, seed):
    from amronet.algorithms.common.forces import inverse_square_obstacle_forces

    rng = np.random.default_rng(seed)
    scans = np.where(rng.random((m, 12)) < 0.4, rng.uniform(0.0, 0.14, (m, 12)), 0.14)
    heading = rng.uniform(-np.pi, np.pi, m)
    hits = obstacle_hits(scans, heading, 0.14)
    push = np.minimum(0.0125 / hits.dist**2, 0.2)
    expected = sum_per_node(hits.row, hits.away * push[:, None], m)
    np.testing.assert_allclose(inverse_square_obstacle_forces(scans, heading, 0.14, 0.0125, 0.2), expected,
                               atol=1e-12)



def _reference_decide(ctl: PotentialField, table):
    """The potential field's decide as plain vector formulas (the laws of the module docstring): movers, velocity."""
    from amronet.algorithms.common.forces import constrained_coverage_forces

    sw, p = ctl.swarm, ctl.params

    def force_on(who):
        return constrained_coverage_forces(table, sw.xy, who, ctl.k_cover, ctl.k_degree, ctl.q_rc, ctl.force_cap,
                                           p.connectivity_k) + ctl.obstacle_force[who]

    state = sw.state[ctl.routers].copy()
    resting = ctl.routers[state == State.REFERENCE]
    change = force_on(resting) - ctl.held_force[resting]
    wake = np.hypot(*change.T) > p.damping * 2 * p.rest_fraction * sw.max_speed[resting]
    state[np.isin(ctl.routers, resting[wake])] = State.EXPLORE
    movers = ctl.routers[state == State.EXPLORE]
    v = ctl.velocity[movers]
    v = clamp_norm(v + (force_on(movers) - p.damping * v) / p.mass * ctl.dt, sw.max_speed[movers])
    return movers, v, int(np.count_nonzero(wake))


def test_compiled_potential_field_decide_follows_the_vector_formulas():
    import copy

    from amronet.algorithms.base import Readings, StepInput

    sim = Simulation(scenario("potential-field", params={"obstacle_forces": False}), seed=4)
    woken_seen = 0
    for k in range(300):
        probe = copy.deepcopy(sim)
        ctl: PotentialField = probe.controller
        if k % 2:  # every other step, let everybody rest first, so that the wake-up rule is exercised too
            probe.swarm.state[ctl.routers] = State.REFERENCE
            ctl.held_force[ctl.routers] = np.random.default_rng(k).normal(0, 0.01, (len(ctl.routers), 2))
        movers, velocity, woken = _reference_decide(ctl, probe.table)
        command = ctl.decide(StepInput(k, probe.t, probe.dt, probe.table, Readings({})))
        np.testing.assert_array_equal(command.movers, movers)
        np.testing.assert_allclose(ctl.velocity[movers], velocity, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(command.speed, np.hypot(*velocity.T), rtol=1e-12, atol=1e-15)
        woken_seen += woken
        sim.step()
    assert woken_seen > 0  # the wake-up rule woke some, and
    assert woken_seen < 150 * 30  # left others resting


def test_a_router_pushed_into_a_wall_comes_to_rest_held_by_it():
    # Howard's field (K = 0) pushes the lone router away from the base node, 0.5 m from the east wall: the wall
    # stops it while it is still in range, so the push never fades; the wall takes it up and the router rests
    sc = scenario("potential-field", params={"connectivity_k": 0, "obstacle_forces": False}, count=1,
                  region=(0.4, 0.4), base=(2.5, 0.0), time_limit=120.0)
    sim = Simulation(sc, seed=1)
    ctl: PotentialField = sim.controller
    router = ctl.routers[0]
    sim.swarm.xy[router] = (2.7, 0.05)  # between the base node and the wall
    sim.table = sim.medium.update(sim.swarm.xy)
    result = sim.run()
    assert result.summary["stop_reason"] == "settled"
    assert sim.swarm.xy[router, 0] > 2.9  # against the wall at x = 3
    assert np.hypot(*ctl.held_force[router]) > 0.02  # and still pushed into it
