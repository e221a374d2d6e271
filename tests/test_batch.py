"""Batched stepping: every run of a batch is the run it would be alone, bit for bit."""

import numpy as np
import pytest

from amronet.engine.radio import make_medium
from amronet.engine.robots import Swarm
from amronet.engine.streams import RunStreams, draw_per_run
from amronet.errors import ScenarioError
from amronet.experiments.fig10 import spreading_scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.batch import BatchSimulation, batchable
from amronet.sweeps.engine import plan_batches
from amronet.sweeps.worker import execute_batch, execute_job


def small_scenario(algorithm: str, map_name: str = "open-6x6", routers: int = 12, time_limit: float = 40.0,
                   **sim) -> dict:
    doc = spreading_scenario(map_name, algorithm, map_name != "open-6x6", time_limit)
    doc["routers"]["count"] = routers
    doc["sim"].update(sim)
    return doc


def assert_same_run(alone, batched) -> None:
    a = {k: v for k, v in alone.summary.items() if k != "wall_time_s"}
    b = {k: v for k, v in batched.summary.items() if k != "wall_time_s"}
    assert a == b
    assert alone.timeseries.keys() == batched.timeseries.keys()
    for key, column in alone.timeseries.items():
        np.testing.assert_array_equal(column, batched.timeseries[key])
    assert alone.network == batched.network  # every robot's final position, state and status, bit for bit
    sa, sb = alone.run, batched.run
    for field in ("xy", "heading", "state", "status", "distance"):
        np.testing.assert_array_equal(getattr(sa.swarm, field), getattr(sb.swarm, field))
    np.testing.assert_array_equal(sa.table.indices, sb.table.indices)


@pytest.mark.parametrize(("algorithm", "map_name"), [
    ("self-spreading", "open-6x6"), ("self-spreading", "obstacles-6x6"),
    ("potential-field", "open-6x6"), ("potential-field", "obstacles-6x6"),
    ("dssa", "open-6x6"), ("dssa", "obstacles-6x6"),
])
def test_a_batched_run_is_the_run_alone(algorithm, map_name):
    sc = load_scenario(small_scenario(algorithm, map_name))
    seeds = [3, 0, 11]
    batched = BatchSimulation(sc, seeds).run()
    assert [r.summary["seed"] for r in batched] == seeds
    for seed, result in zip(seeds, batched, strict=True):
        assert_same_run(Simulation(sc, seed).run(), result)


def test_runs_that_stop_at_different_times_leave_the_batch_unchanged():
    """Runs that reach the coverage target or settle early stop early; the others go on as if alone."""
    sc = load_scenario(small_scenario("self-spreading", routers=4, time_limit=150.0, coverage_target=0.2))
    seeds = list(range(6))
    batched = BatchSimulation(sc, seeds).run()
    stops = {(r.summary["stop_reason"], r.summary["steps"]) for r in batched}
    assert len(stops) > 2, stops  # the runs really did stop at different steps
    for seed, result in zip(seeds, batched, strict=True):
        assert_same_run(Simulation(sc, seed).run(), result)
    settled = load_scenario(small_scenario("self-spreading", routers=3, time_limit=300.0))
    for seed, result in zip([5, 6], BatchSimulation(settled, [5, 6]).run(), strict=True):
        assert result.summary["stop_reason"] == "settled"
        assert_same_run(Simulation(settled, seed).run(), result)


def test_the_potential_field_reports_its_own_wakeups_per_run():
    sc = load_scenario(small_scenario("potential-field", routers=6, time_limit=120.0))
    batched = BatchSimulation(sc, [1, 2]).run()
    alone = [Simulation(sc, s).run().summary["wakeups"] for s in (1, 2)]
    assert [r.summary["wakeups"] for r in batched] == alone
    assert sum(alone) > 0  # else the test shows nothing


def test_dssa_reports_how_its_routers_stopped_per_run():
    sc = load_scenario(small_scenario("dssa", "obstacles-6x6", routers=20))
    seeds = [1, 2, 3]
    batched = [r.summary for r in BatchSimulation(sc, seeds).run()]
    alone = [Simulation(sc, s).run().summary for s in seeds]
    for key in ("stopped_by_oscillation", "stopped_by_stability", "expected_density_mu"):
        assert [b[key] for b in batched] == [a[key] for a in alone]
    assert len({a["stopped_by_stability"] for a in alone}) > 1  # the runs differ: a sum over them would show


def test_what_cannot_be_batched_is_refused_in_one_line():
    agents = load_scenario("agent-assisted-office")
    assert not batchable(agents)
    with pytest.raises(ScenarioError, match="cannot be stepped in batches; run them one by one"):
        BatchSimulation(agents, [0, 1])
    with pytest.raises(ScenarioError, match="seeds: a batch needs at least one seed"):
        BatchSimulation(load_scenario(small_scenario("self-spreading")), [])


def test_run_streams_draw_each_run_in_its_own_order():
    starts = np.array([0, 3, 3, 7])  # run 1 has no robots
    streams = RunStreams([np.random.default_rng(s) for s in (10, 11, 12)], starts)
    who = np.array([5, 0, 6, 2])  # runs 2, 0, 2, 0: need not be sorted
    normal, uniform = draw_per_run(streams, who, lambda g, m: (g.normal(size=m), g.uniform(size=m)))
    r0, r2 = np.random.default_rng(10), np.random.default_rng(12)
    n0, u0 = r0.normal(size=2), r0.uniform(size=2)
    n2, u2 = r2.normal(size=2), r2.uniform(size=2)
    np.testing.assert_array_equal(normal, [n2[0], n0[0], n2[1], n0[1]])
    np.testing.assert_array_equal(uniform, [u2[0], u0[0], u2[1], u0[1]])
    empty = draw_per_run(streams, np.zeros(0, dtype=np.int64), lambda g, m: (g.normal(size=m),))
    assert empty[0].shape == (0,)
    with pytest.raises(ValueError, match="starts needs 3 entries"):
        RunStreams([np.random.default_rng(0)] * 2, np.array([0, 1]))


def test_swarm_blocks_and_table_blocks_are_the_runs_own():
    sc = load_scenario(small_scenario("self-spreading"))
    runs = [Simulation(sc, s) for s in (0, 1)]
    joined = Swarm.concat([r.swarm for r in runs])
    block = slice(len(runs[0].swarm), len(joined))
    view = joined.rows(block)
    view.xy[0, 0] += 1.0  # a view: writes through
    assert joined.xy[block.start, 0] == view.xy[0, 0]
    copy = view.copy()
    copy.xy[0, 0] += 1.0
    assert joined.xy[block.start, 0] != copy.xy[0, 0]
    medium = make_medium("unit-disk", 1.0)
    groups = np.repeat([0, 1], [len(r.swarm) for r in runs])
    own = medium.update(joined.xy[block]).indptr, medium.update(joined.xy[block]).indices
    table = medium.update(joined.xy, groups).block(block)
    np.testing.assert_array_equal(table.indptr, own[0])
    np.testing.assert_array_equal(table.indices, own[1])
    other = runs[0].swarm
    other.models = (*other.models, other.models[0])
    with pytest.raises(ValueError, match="different robot models"):
        Swarm.concat([runs[1].swarm, other])


def test_plan_batches_groups_runs_of_one_batchable_scenario():
    ss = small_scenario("self-spreading")
    alone = load_scenario("agent-assisted-office").model_dump(mode="json")
    pending = [("a", s, ss) for s in range(5)] + [("b", s, alone) for s in range(3)] + [("c", 0, ss)]
    jobs = plan_batches(pending, slots=2, max_size=2)
    assert sorted(k for ks in jobs for k in ks) == list(range(9))
    assert sorted(map(len, jobs), reverse=True) == [len(ks) for ks in jobs]  # larger first
    assert sorted(jobs) == [[0, 1], [2, 3], [4], [5], [6], [7], [8]]
    assert plan_batches(pending[:5], slots=4) == [[0, 1], [2], [3], [4]]  # every slot gets work
    assert plan_batches(pending[:5], slots=1) == [[0, 1, 2, 3, 4]]


def test_a_batch_job_gives_each_run_its_own_outcome():
    doc = load_scenario(small_scenario("self-spreading", time_limit=5.0)).to_dict()
    outcomes = execute_batch({"scenario": doc, "seeds": [0, 1]})
    alone = [execute_job({"scenario": doc, "seed": s}) for s in (0, 1)]
    assert [o["summary"] for o in outcomes] == [o["summary"] for o in alone]
    assert [o["timeseries"] for o in outcomes] == [o["timeseries"] for o in alone]
    bad = {**doc, "map": "no-such-map"}
    failed = execute_batch({"scenario": bad, "seeds": [0, 1]})
    assert [o["status"] for o in failed] == ["failed", "failed"]
    assert failed[0]["error"] == execute_job({"scenario": bad, "seed": 0})["error"]
