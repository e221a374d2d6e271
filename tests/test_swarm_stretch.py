"""Stretches of self-spreading and potential-field loops (amronet.algorithms.common.swarm_stretch) against step-by-step
runs."""

import numpy as np
import pytest

from amronet.algorithms.common.swarm_stretch import SwarmStretch
from amronet.engine.robots import State
from amronet.scenario import load_scenario
from amronet.sim import BatchSimulation, Simulation

CASES = {
    # runs that settle at different times and leave the batch (each stretch stops after a run settles)
    "self-spreading, runs settle": ("self-spreading-6x6", (1, 2, 3, 4), {"sim.time_limit": 750}),
    # two bases: the stretches start the triangles of the none and local rules themselves
    "self-spreading, two bases, no optimization": ("self-spreading-office", (1, 2),
                                                  {"sim.time_limit": 150, "algorithm.params.triangular": "none"}),
    "self-spreading, two bases, local rule": ("self-spreading-office", (5, 6), {"sim.time_limit": 150}),
    # the global rule asks the network's components: its steps end the stretches before them
    "self-spreading, global rule, without collisions": ("self-spreading-office", (3, 4), {
        "sim.time_limit": 100, "algorithm.params.triangular": "global", "sim.robot_collisions": False}),
    # routers at rest wake up again: runs that stay in the books while settled, unsettle and settle again
    # the walk rules' headings inside the stretch (a kernel of their own; the paper's random walk has its own)
    **{f"self-spreading, walk {walk}": ("self-spreading-office", (1, 2), {
        "sim.time_limit": 120, "algorithm.params.walk": walk}) for walk in ("straight", "growth", "guided")},
    "potential field, settled runs go on": ("potential-field-6x6", (1, 2, 3), {
        "sim.time_limit": 300, "sim.stop_when_settled": False, "routers.count": 10}),
    "potential field, obstacle forces": ("potential-field-obstacles-6x6", (1, 2), {"sim.time_limit": 60}),
    "potential field without obstacle forces": ("potential-field-6x6", (4, 5),
                                                {"sim.time_limit": 60, "algorithm.params.obstacle_forces": False}),
}


def _run(preset, seeds, overrides, stretch):
    sim = BatchSimulation(load_scenario(preset, overrides), seeds)
    if not stretch:
        sim.compiled.stretches = False
    return sim, sim.run()


@pytest.mark.parametrize("name", sorted(CASES))
def test_a_batch_in_stretches_is_the_batch_step_by_step(name):
    preset, seeds, overrides = CASES[name]
    fast, fast_results = _run(preset, seeds, overrides, True)
    slow, slow_results = _run(preset, seeds, overrides, False)
    stretch = fast.compiled.stretcher
    assert isinstance(stretch, SwarmStretch) and stretch.steps > fast.steps // 2
    for field in ("xy", "heading", "state", "status", "distance"):
        np.testing.assert_array_equal(getattr(fast.swarm, field), getattr(slow.swarm, field))
    assert fast.steps == slow.steps
    for a, b in zip(fast_results, slow_results, strict=True):
        assert a.network == b.network
        for k in a.timeseries:
            np.testing.assert_array_equal(a.timeseries[k], b.timeseries[k])
        assert {k: v for k, v in a.summary.items() if k != "wall_time_s"} == \
            {k: v for k, v in b.summary.items() if k != "wall_time_s"}


def test_stretches_end_where_runs_settle_and_start_triangles_but_the_global_rules():
    settle, _ = _run(*CASES["self-spreading, runs settle"], True)
    assert settle.compiled.stretcher.ends["settling"] > 0
    assert sum(r.stop_reason == "settled" for r in settle.runs) > 1
    for case in ("self-spreading, two bases, no optimization", "self-spreading, two bases, local rule"):
        triangles, _ = _run(*CASES[case], True)
        assert triangles.compiled.stretcher.ends["candidates"] == 0 and triangles.compiled.triangles_started > 0
        assert (triangles.swarm.state == State.TRIANGLE_SETTLED).any()
    global_rule, _ = _run("self-spreading-office", (1, 2),
                          {"sim.time_limit": 150, "algorithm.params.triangular": "global"}, True)
    assert global_rule.compiled.stretcher.ends["candidates"] > 0 and global_rule.compiled.triangles_started == 0
    woken, _ = _run(*CASES["potential field, settled runs go on"], True)
    assert woken.compiled.stretcher.ends["settling"] > 0 and woken.controller.wakeups.sum() > 0


def test_a_single_run_takes_stretches_too():
    sim = Simulation(load_scenario("self-spreading-6x6", {"sim.time_limit": 60}), 3)
    sim.run()
    assert sim.compiled.stretcher is not None and sim.compiled.stretcher.steps > 0


def test_no_stretch_where_the_table_does_not_hold_every_pair():
    sim = Simulation(load_scenario("self-spreading-6x6", {"sim.time_limit": 5, "radio.model": "log-distance"}), 3)
    assert sim.compiled is not None and sim.compiled.stretcher is None


def test_without_compiled_draws_the_walkers_draw_through_numpy_and_take_no_stretch(monkeypatch):
    # (a numba without its copy of numpy's ziggurat tables): the same run, step by step
    from amronet.engine import bitgen

    sc = load_scenario("self-spreading-6x6", {"sim.time_limit": 60})
    usual = Simulation(sc, 5)
    monkeypatch.setattr(bitgen, "AVAILABLE", False)
    plain = Simulation(sc, 5)
    assert plain.compiled.streams is None and plain.compiled.stretcher is None
    assert usual.compiled.streams is not None
    a, b = usual.run(), plain.run()
    np.testing.assert_array_equal(usual.swarm.xy, plain.swarm.xy)
    assert a.network == b.network


@pytest.mark.parametrize(("preset", "overrides"), [("self-spreading-office", {"sim.time_limit": 60}),
                                                  ("potential-field-6x6", {"sim.time_limit": 60})])
def test_the_books_rule_the_kernel_watches_is_the_controllers(preset, overrides):
    sim = Simulation(load_scenario(preset, overrides), 2)
    lookup, robots = sim.controller.settling_rule()
    for _ in range(3):  # at the start, part-way, at the end
        np.testing.assert_array_equal(lookup[sim.swarm.state] & robots, sim.controller.unsettled())
        for _ in range(200):
            sim.step()


@pytest.mark.parametrize("overrides", [{}, {"sim.robot_collisions": False}])
def test_advance_takes_stretches_and_leaves_what_as_many_steps_leave(overrides):
    # a single run with two bases (stretches end before triangles) and a batch: Loop.advance against Loop.step
    for make in (lambda: Simulation(load_scenario("self-spreading-office", overrides), 2),
                 lambda: BatchSimulation(load_scenario("self-spreading-6x6", overrides), (1, 2))):
        fast, slow = make(), make()
        fast.advance(400)
        for _ in range(400):
            slow.step()
        assert fast.steps == slow.steps == 400 and fast.compiled.stretcher.steps > 200
        for field in ("xy", "heading", "state", "status", "distance"):
            np.testing.assert_array_equal(getattr(fast.swarm, field), getattr(slow.swarm, field))
        for field in ("indptr", "indices", "dist"):
            np.testing.assert_array_equal(getattr(fast.table, field), getattr(slow.table, field))


def test_advance_steps_one_by_one_where_no_stretch_applies():
    sim = Simulation(load_scenario("self-spreading-6x6", {"radio.model": "log-distance"}), 3)
    sim.advance(7)
    assert sim.steps == 7 and sim.compiled.stretcher is None
