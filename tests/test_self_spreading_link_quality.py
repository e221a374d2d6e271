"""Self-spreading's location-free rules: the link-quality stop rule and the run-and-tumble triangle rule."""

from __future__ import annotations

import numpy as np
import pytest

from amronet.algorithms.base import Readings, StepInput
from amronet.algorithms.common.link_quality import MarginSearch, MarginSmoother, anchor_margins, strongest_references
from amronet.engine.network import connected_to
from amronet.engine.robots import Role, State
from amronet.engine.table import NeighbourTable
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import BatchSimulation, Simulation

LQ = {"algorithm.params.stop_rule": "link-quality"}
LQ_BOTH = {**LQ, "algorithm.params.triangle_rule": "link-quality"}


def two_bases(**params) -> dict:
    return {
        "map": "open-6x6", "radio": {"r_c": 1.0},
        "algorithm": {"name": "self-spreading", "params": {"triangular": "local", **params}},
        "base_stations": [{"x": -2.0, "y": 0.0, "region": [0.8, 0.8]}, {"x": 2.0, "y": 0.0, "region": [0.8, 0.8]}],
        "routers": {"count": 40, "robot": {"radius": 0.045, "max_speed": 0.4, "sensor_beams": 12,
                                             "sensor_range": 0.14}},
    }


def table_of(xy: np.ndarray, margin: np.ndarray, dist: np.ndarray) -> NeighbourTable:
    """A hand-built neighbour table: ``margin[i, j]`` (nan: no link) and ``dist[i, j]`` for every pair."""
    n = len(xy)
    linked = np.isfinite(margin) & ~np.eye(n, dtype=bool)
    rows, cols = np.nonzero(linked)
    indptr = np.concatenate([[0], np.cumsum(linked.sum(axis=1))]).astype(np.int64)
    return NeighbourTable(xy=xy, r=1.0, indptr=indptr, indices=cols.astype(np.int32), dist=dist[rows, cols],
                          threshold_dbm=-30.0, link_margin=margin[rows, cols])


def blind_readings(sim: Simulation) -> Readings:
    """Range readings of every router that see nothing."""
    sw = sim.swarm
    routers = np.flatnonzero(sw.role == Role.ROUTER)
    model = int(sw.model[routers[0]])
    scans = np.full((len(routers), sw.models[model].sensor_beams), sw.models[model].sensor_range)
    return Readings({model: (routers, scans)})


# -- the defaults are the paper's rules, bit for bit ----------------------------------------------------------------
@pytest.mark.parametrize(("doc", "seed", "time_limit"), [("self-spreading-obstacles-6x6", 7, 20.0),
                                                         (two_bases(), 4, 10.0)])
def test_explicit_default_rules_change_nothing(doc, seed, time_limit):
    sc = load_scenario(doc, overrides={"sim.time_limit": time_limit})
    explicit = sc.with_overrides({"algorithm.params.stop_rule": "distance",
                                  "algorithm.params.triangle_rule": "geometric"})
    a, b = Simulation(sc, seed).run(), Simulation(explicit, seed).run()
    assert a.files()["network.json"] == b.files()["network.json"]
    assert a.timeseries_csv() == b.timeseries_csv()


# -- the stop rule --------------------------------------------------------------------------------------------------
def test_link_quality_stop_reads_no_positions():
    """Two controllers, the same margins step by step: one sees other positions and distances, same decisions."""
    sc = load_scenario("self-spreading-6x6", overrides={"routers.count": 8, **LQ})
    a, b = Simulation(sc, 3), Simulation(sc, 3)
    n = len(a.swarm)
    gen = np.random.default_rng(0)
    b.swarm.xy[:] = gen.uniform(-3.0, 3.0, (n, 2))  # the controller's own view of every node's position
    upper = np.triu(gen.uniform(0.0, 12.0, (n, n)), 1)
    fade = np.triu(gen.uniform(0.05, 0.4, (n, n)), 1)
    stops = []
    for k in range(60):
        margin = upper - fade * k + np.triu(gen.normal(0.0, 0.7, (n, n)), 1)
        margin = np.triu(np.where(margin >= 0.0, margin, np.nan), 1)  # links below the threshold are not heard
        margin = margin + margin.T
        ta = table_of(a.swarm.xy.copy(), margin, gen.uniform(0.0, 1.0, (n, n)))
        tb = table_of(b.swarm.xy.copy(), margin, gen.uniform(5.0, 9.0, (n, n)))
        a.controller.decide(StepInput(k, 0.1 * k, 0.1, ta, blind_readings(a)))
        b.controller.decide(StepInput(k, 0.1 * k, 0.1, tb, blind_readings(b)))
        np.testing.assert_array_equal(a.swarm.state, b.swarm.state)
        np.testing.assert_array_equal(a.swarm.status, b.swarm.status)
        np.testing.assert_array_equal(a.controller.current, b.controller.current)
        stops.append(int((a.swarm.state == State.REFERENCE).sum()))
    assert 0 < stops[10] and stops[-1] > stops[10], stops  # decisions were made, and not all at once


def test_one_faded_sample_does_not_stop_a_router_a_sustained_weak_link_or_a_breaking_one_does():
    sc = load_scenario("self-spreading-6x6", overrides={"routers.count": 1, **LQ})  # stop 3 dB, loss 1 dB, 0.5 s
    xy = np.array([[0.0, 0.0], [0.5, 0.0]])

    def states(margins):
        sim = Simulation(sc, 0)
        out = []
        for k, m in enumerate(margins):
            table = table_of(xy, np.array([[np.nan, m], [m, np.nan]]), np.full((2, 2), 0.5))
            sim.controller.decide(StepInput(k, 0.1 * k, 0.1, table, blind_readings(sim)))
            out.append(int(sim.swarm.state[1]))
        return out

    faded = states([8.0] * 10 + [2.0] + [8.0] * 10)  # one sample between the thresholds
    assert State.REFERENCE not in faded
    sustained = states([8.0] * 10 + [2.0] * 20)
    first = sustained.index(State.REFERENCE)
    assert 11 < first < 30  # not at the first weak sample, but soon
    breaking = states([8.0] * 10 + [0.5])  # below the loss threshold: at once
    assert breaking[-1] == State.REFERENCE and State.REFERENCE not in breaking[:-1]
    unheard = states([8.0] * 5 + [np.nan] * 5)  # no reference heard: walks on, history restarts
    assert State.REFERENCE not in unheard


def test_margin_smoother_restarts_when_nothing_is_heard():
    s = MarginSmoother(3, dt=0.1, smoothing_s=0.5)
    who = np.array([0, 2])
    assert s.update(who, np.array([5.0, 4.0])).tolist() == [5.0, 4.0]  # no history: the sample itself
    out = s.update(who, np.array([1.0, -np.inf]))
    assert out[0] == pytest.approx(5.0 - 4.0 * (1.0 - np.exp(-0.2)))
    assert np.isnan(out[1]) and np.isnan(s.value[1])
    assert s.update(who, np.array([1.0, 7.0]))[1] == 7.0
    assert MarginSmoother(1, 0.1, 0.0).alpha == 1.0


def test_tracking_by_signal_keeps_the_current_reference_and_else_takes_the_strongest():
    xy = np.zeros((4, 2))
    margin = np.full((4, 4), np.nan)
    for i, j, m in ((3, 0, 2.0), (3, 1, 6.0), (3, 2, 4.0)):
        margin[i, j] = margin[j, i] = m
    table = table_of(xy, margin, np.ones((4, 4)))
    is_ref = np.array([True, True, True, False])
    status = np.array([0, 0, 1, -1])
    view = strongest_references(table, np.array([3]), np.array([0]), is_ref, status)
    assert view.current.tolist() == [0] and view.best_margin.tolist() == [6.0]  # keeps 0 while it hears it
    assert view.other.tolist() == [2] and view.other_margin.tolist() == [4.0]
    view = strongest_references(table, np.array([3]), np.array([-1]), is_ref, status)
    assert view.current.tolist() == [1]  # none yet: the strongest
    assert anchor_margins(table, np.array([3]), np.array([[2, 0]])).tolist() == [[4.0, 2.0]]
    assert anchor_margins(table, np.array([0]), np.array([[2, -1]])).tolist() == [[-np.inf, -np.inf]]


def test_under_the_unit_disk_routers_stop_where_the_margin_says():
    """No smoothing: a router stops within one step beyond the distance at which the budget's margin is 3 dB."""
    sc = load_scenario("self-spreading-6x6", overrides={**LQ, "algorithm.params.smoothing_s": 0.0})
    sim = Simulation(sc, 1)
    budget = sim.medium.budget
    d_stop = budget.r_c * 10.0 ** (-3.0 / (10.0 * budget.exponent))
    assert float(budget.margin_db(d_stop)) == pytest.approx(3.0)
    step = float(sim.swarm.max_speed.max()) * sc.sim.dt
    stopped_at = []
    for _ in range(1200):
        before = sim.swarm.deployed.copy()
        xy = sim.swarm.xy.copy()
        sim.step()
        for i in np.flatnonzero(sim.swarm.deployed & ~before):
            stopped_at.append(np.linalg.norm(xy[before] - xy[i], axis=1).min())
    assert len(stopped_at) >= 20
    assert min(stopped_at) > d_stop - 1e-9 and max(stopped_at) <= d_stop + step + 1e-9, (d_stop, stopped_at)


def test_under_the_unit_disk_smoothed_stops_lie_between_the_two_thresholds():
    sc = load_scenario("self-spreading-6x6", overrides=LQ)
    sim = Simulation(sc, 2)
    budget = sim.medium.budget
    d_stop, d_loss = (budget.r_c * 10.0 ** (-m / (10.0 * budget.exponent)) for m in (3.0, 1.0))
    step = float(sim.swarm.max_speed.max()) * sc.sim.dt
    stopped_at = []
    for _ in range(1200):
        before = sim.swarm.deployed.copy()
        xy = sim.swarm.xy.copy()
        sim.step()
        stopped_at += [np.linalg.norm(xy[before] - xy[i], axis=1).min()
                       for i in np.flatnonzero(sim.swarm.deployed & ~before)]
    assert len(stopped_at) >= 20
    assert max(stopped_at) <= d_loss + step + 1e-9
    assert np.median(stopped_at) > d_stop  # the moving average lags: later than the raw margin would stop


def test_link_quality_references_stay_linked_on_a_real_map_under_multi_wall():
    sc = load_scenario("self-spreading-autolab", overrides={"radio.model": "multi-wall", "sim.time_limit": 60.0,
                                                             **LQ_BOTH})
    sim = Simulation(sc, 1)
    for k in range(600):
        sim.step()
        if k % 50 == 49:
            refs = sim.swarm.state == State.REFERENCE
            linked = connected_to(sim.table, sim.bases, sim.swarm.deployed)
            assert linked[refs].all(), f"a reference lost its path to the base at step {k}"
    assert (sim.swarm.state == State.REFERENCE).sum() >= 5


def test_link_quality_runs_batched_are_the_runs_alone():
    sc = load_scenario(two_bases(stop_rule="link-quality", triangle_rule="link-quality"),
                       overrides={"sim.time_limit": 30.0})
    seeds = [4, 1]
    for seed, result in zip(seeds, BatchSimulation(sc, seeds).run(), strict=True):
        alone = Simulation(sc, seed).run()
        assert alone.network == result.network
        assert alone.timeseries_csv() == result.timeseries_csv()


# -- the triangle rule ----------------------------------------------------------------------------------------------
def test_run_and_tumble_triangles_join_two_networks_and_stay_linked():
    sc = load_scenario(two_bases(stop_rule="link-quality", triangle_rule="link-quality"),
                       overrides={"sim.time_limit": 90.0})
    sim = Simulation(sc, 4)
    search = sim.controller.search
    settled = []
    for _ in range(900):
        before = sim.swarm.state.copy()
        sim.step()
        sw = sim.swarm
        linked = connected_to(sim.table, sim.bases, sw.deployed)
        assert linked[sw.deployed].all(), "a deployed router lost its path to the base stations"
        for i in np.flatnonzero((sw.state == State.TRIANGLE_SETTLED) & (before == State.TRIANGLE)):
            settled.append(search.last[i].copy())
    sw = sim.swarm
    assert set(np.unique(sw.status[sw.deployed]).tolist()) == {0, 1}
    assert len(settled) >= 3, "the two networks never met"
    margins = np.array(settled)
    assert np.isfinite(margins).all(axis=1).mean() >= 0.8  # nearly all hear both of their references
    p = sim.controller.params
    on_target = np.all(np.abs(margins - p.stop_margin_db) <= p.triangle_tolerance_db, axis=1)
    assert on_target.any()
    assert sim.metrics().components == 1


def test_margin_search_keeps_runs_that_pay_and_settles_by_its_rules():
    s = MarginSearch(4, target_db=3.0, tolerance_db=1.0, loss_db=1.0, give_up_steps=3, max_s=2.0)
    who = np.arange(4)
    s.start(who, np.array([[0, 1]] * 4), t=0.0)
    tumble, reverse, done = s.step(who, np.array([[2.0, 0.1], [0.5, 0.2], [1.5, 0.3], [3.5, 2.5]]), t=0.0)
    assert done.tolist() == [False, False, False, True]  # only the last is on target; below loss from the start
    assert not tumble.any() and not reverse.any()  # the first step of a run always pays
    tumble, reverse, done = s.step(who[:3], np.array([[2.2, 0.5], [0.4, 0.1], [0.9, -np.inf]]), t=0.1)
    assert tumble.tolist() == [False, True, False]  # f went down: keep going; up: tumble
    assert reverse.tolist() == [False, False, True]  # a link was lost: back the way it came
    assert done.tolist() == [False, False, True]  # robot 2's first link fell below the loss threshold
    for k in range(2, 5):  # robot 1 makes no progress: gives up after 3 steps without a new best
        _, _, done = s.step(who[1:2], np.array([[0.4, 0.1]]), t=0.1 * k)
    assert done.tolist() == [True]
    _, _, done = s.step(who[:1], np.array([[2.3, 0.6]]), t=2.0)  # out of time
    assert done.tolist() == [True]


# -- parameters -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("params", "field"), [
    ({"stop_margin_db": 1.0, "loss_margin_db": 1.0}, "stop_margin_db"),
    ({"stop_margin_db": 2.0, "loss_margin_db": 3.0}, "stop_margin_db"),
    ({"loss_margin_db": -0.5}, "loss_margin_db"),
    ({"smoothing_s": -1.0}, "smoothing_s"),
    ({"stop_rule": "rssi"}, "stop_rule"),
    ({"triangle_rule": "gradient"}, "triangle_rule"),
    ({"triangle_tolerance_db": 0.0}, "triangle_tolerance_db"),
    ({"triangle_max_s": -1.0}, "triangle_max_s"),
])
def test_bad_link_quality_parameters_name_their_field(params, field):
    with pytest.raises(ScenarioError) as err:
        load_scenario("self-spreading-6x6", overrides={f"algorithm.params.{k}": v for k, v in params.items()})
    assert err.value.field == f"algorithm.params.{field}"
    assert "\n" not in str(err.value)
