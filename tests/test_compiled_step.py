"""The compiled steps (amronet.algorithms.self_spreading.fast) against the reference phases, bit for bit."""

import numpy as np
import pytest

from amronet.algorithms.agent_assisted.controller import AgentAssisted
from amronet.algorithms.agent_assisted.fast import CompiledAgents
from amronet.algorithms.potential_field.fast import CompiledField
from amronet.algorithms.self_spreading import fast as compiled_step
from amronet.algorithms.self_spreading.controller import SelfSpreading
from amronet.algorithms.self_spreading.fast import CompiledSpreading
from amronet.engine.robots import State
from amronet.experiments.walks import walk_scenario
from amronet.scenario import load_scenario
from amronet.sim import BatchSimulation, Simulation

CASES = {
    "open 6x6": ("self-spreading-6x6", 3, {"sim.time_limit": 40}),
    "obstacles, global rule": ("self-spreading-obstacles-6x6", 5,
                               {"sim.time_limit": 40, "algorithm.params.triangular": "global"}),
    "autolab floor plan": ("self-spreading-autolab", 1, {"sim.time_limit": 40}),
    "office, two bases, local rule": ("self-spreading-office", 2, {"sim.time_limit": 100}),
    "office, no optimization": ("self-spreading-office", 3,
                                {"sim.time_limit": 100, "algorithm.params.triangular": "none"}),
    "office, global rule": ("self-spreading-office", 4,
                            {"sim.time_limit": 100, "algorithm.params.triangular": "global"}),
    "office, greedy only": ("self-spreading-office", 4, {"sim.time_limit": 40, "algorithm.params.triangular": "off"}),
    "multi-wall radio": ("self-spreading-office", 5, {"sim.time_limit": 40, "radio.model": "multi-wall"}),
    "no body collisions": ("self-spreading-office", 6, {"sim.time_limit": 40, "sim.robot_collisions": False}),
    "base station by a wall": ("self-spreading-obstacles-6x6", 7,
                               {"sim.time_limit": 40, "base_stations": [{"x": -2.7, "y": 0.0}]}),
    "potential field": ("potential-field-6x6", 1, {"sim.time_limit": 40}),
    "potential field, obstacles": ("potential-field-obstacles-6x6", 2, {"sim.time_limit": 40}),
    "Howard's field (K = 0)": ("potential-field-obstacles-6x6", 3,
                               {"sim.time_limit": 40, "algorithm.params.connectivity_k": 0}),
    "potential field without obstacle forces": ("potential-field-obstacles-6x6", 4,
                                                {"sim.time_limit": 40, "algorithm.params.obstacle_forces": False}),
    "potential field on autolab": ("potential-field-6x6", 6, {"sim.time_limit": 40, "map": "autolab",
                                                            "base_stations": [{"x": 3.0, "y": 3.0}]}),
    **{f"walk {walk}, obstacles, global rule": ("self-spreading-obstacles-6x6", 5, {
        "sim.time_limit": 40, "algorithm.params.triangular": "global", "algorithm.params.walk": walk})
       for walk in ("straight", "growth", "guided")},
    **{f"walk {walk}, office, two bases": ("self-spreading-office", 2, {
        "sim.time_limit": 150, "algorithm.params.triangular": "none", "algorithm.params.walk": walk})
       for walk in ("straight", "growth", "guided")},
    **{f"walk {walk}, hospital floor plan": (walk_scenario("hospital_section", walk, 60.0), 80_000, {})
       for walk in ("random", "straight", "growth", "guided")},
    "walk growth, multi-wall radio": ("self-spreading-office", 5, {"sim.time_limit": 40, "radio.model": "multi-wall",
                                                                   "algorithm.params.walk": "growth"}),
    "link-quality stop rule": ("self-spreading-6x6", 3, {"sim.time_limit": 40,
                                                         "algorithm.params.stop_rule": "link-quality"}),
    "link-quality stop rule, two bases": ("self-spreading-office", 2, {
        "sim.time_limit": 150, "algorithm.params.triangular": "none", "algorithm.params.stop_rule": "link-quality"}),
    "link-quality triangles": ("self-spreading-office", 2, {
        "sim.time_limit": 150, "algorithm.params.triangular": "none",
        "algorithm.params.triangle_rule": "link-quality"}),
    "link-quality rules, guided walk, hospital floor plan": (walk_scenario("hospital_section", "guided", 60.0), 3, {
        "algorithm.params.stop_rule": "link-quality", "algorithm.params.triangle_rule": "link-quality"}),
    "link-quality rules, multi-wall radio with packet loss": ("self-spreading-office", 5, {
        "sim.time_limit": 30, "radio.model": "multi-wall", "radio.packet_loss": True, "radio.shadowing_db": 4.0,
        "algorithm.params.stop_rule": "link-quality", "algorithm.params.triangle_rule": "link-quality"}),
    "agents, paper's random explorer": ("agent-assisted-office", 1, {"sim.time_limit": 150}),
    "agents, frontier explorer": ("agent-assisted-office", 2, {"sim.time_limit": 200, "radio.r_c": 4.0,
                                                               "algorithm.params.explorer": "frontier"}),
    "agents, four bases, triangles": ("agent-assisted-office-4bs", 3, {"sim.time_limit": 120, "agents.per_base": 1,
                                                                      "algorithm.params.explorer": "frontier"}),
    "agents, four bases, global rule": ("agent-assisted-office-4bs", 4,
                                        {"sim.time_limit": 120, "agents.per_base": 1,
                                         "algorithm.params.explorer": "frontier",
                                         "algorithm.params.triangular": "global"}),
    "agents, wall-follow on depot": ("agent-assisted-office", 5, {
        "sim.time_limit": 150, "map": "depot", "radio.r_c": 3.0, "algorithm.params.explorer": "wall-follow",
        "base_stations": [{"x": 1.0, "y": 1.0}, {"x": 20.0, "y": 8.0}]}),
    "agents, random-escape, multi-wall radio": ("agent-assisted-office", 6, {
        "sim.time_limit": 150, "radio.model": "multi-wall", "algorithm.params.explorer": "random-escape"}),
    "agents, no body collisions": ("agent-assisted-office", 7, {"sim.time_limit": 150, "sim.robot_collisions": False,
                                                                "algorithm.params.explorer": "frontier"}),
}


def _state(sim):
    sw = sim.swarm
    return sw.xy, sw.heading, sw.state, sw.status, sw.distance


def _walkers_memory(sim):
    """What self-spreading's walk and stop rules keep per router (edge following, growth, smoothed margins)."""
    c = sim.controller
    if not isinstance(c, SelfSpreading):
        return ()
    smoothed = () if c.smoother is None else (c.smoother.value,)
    return (c.walker.follow, c.walker.side, c.walker.deployed_at, *smoothed)


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_step_gives_the_reference_run_bit_for_bit(name):
    preset, seed, overrides = CASES[name]
    sc = load_scenario(preset, overrides)
    compiled, reference = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    assert compiled.compiled is not None and reference.compiled is None
    a, b = compiled.run(), reference.run()
    for x, y in zip(_state(compiled) + _walkers_memory(compiled), _state(reference) + _walkers_memory(reference),
                    strict=True):
        np.testing.assert_array_equal(x, y)
    for name in ("current", "disabled", "velocity", "rest_count", "held_force", "wakeups", "left", "refused",
                 "released_by"):
        if hasattr(reference.controller, name):
            np.testing.assert_array_equal(getattr(compiled.controller, name), getattr(reference.controller, name))
    grid = getattr(getattr(reference.controller, "explorer", None), "grid", None)
    if grid is not None:  # the frontier explorer's knowledge
        np.testing.assert_array_equal(compiled.controller.explorer.grid.score, grid.score)
        np.testing.assert_array_equal(compiled.controller.explorer.visited, reference.controller.explorer.visited)
    assert compiled.rows == reference.rows and a.network == b.network
    assert {k: v for k, v in a.summary.items() if k != "wall_time_s"} == \
        {k: v for k, v in b.summary.items() if k != "wall_time_s"}


def test_it_steps_through_triangular_deployments_by_the_controllers_rules(monkeypatch):
    """Steps in which a triangle may start go through the controller's own Python rules; the runs still agree."""
    calls = []
    settle = SelfSpreading.settle_explorers

    def counting(self, *args):
        calls.append(1)
        return settle(self, *args)

    monkeypatch.setattr(SelfSpreading, "settle_explorers", counting)
    sc = load_scenario("self-spreading-office", {"sim.time_limit": 150, "algorithm.params.triangular": "none"})
    compiled, reference = Simulation(sc, 2), Simulation(sc, 2, step="reference")
    compiled.compiled.stretches = False  # (stretches start these triangles in their kernel: test_swarm_stretch.py)
    compiled.run()
    in_compiled = len(calls)
    reference.run()
    assert 0 < in_compiled < compiled.steps  # only the steps in which a triangle may start
    assert np.count_nonzero(compiled.swarm.state == State.TRIANGLE_SETTLED) > 0
    np.testing.assert_array_equal(compiled.swarm.xy, reference.swarm.xy)
    np.testing.assert_array_equal(compiled.swarm.state, reference.swarm.state)


def _count_calls(monkeypatch, names):
    calls = dict.fromkeys(names, 0)
    for name in calls:
        original = getattr(AgentAssisted, name)

        def counting(self, *args, _name=name, _original=original):
            calls[_name] += 1
            return _original(self, *args)

        monkeypatch.setattr(AgentAssisted, name, counting)
    return calls


def test_agents_that_act_and_routers_that_drive_go_through_the_controllers_rules(monkeypatch):
    """Steps in which an agent acts go through ``decide_tracked``; while a triangle router drives, the compiled step
    senses it and the controller steers it (``movers_command``); no step goes through the phases, and the runs agree."""
    calls = _count_calls(monkeypatch, ("decide", "decide_tracked", "movers_command"))
    sc = load_scenario("agent-assisted-office-4bs", {"sim.time_limit": 120, "agents.per_base": 1,
                                                     "algorithm.params.explorer": "frontier"})
    compiled, reference = Simulation(sc, 3), Simulation(sc, 3, step="reference")
    assert isinstance(compiled.compiled, CompiledAgents)
    compiled.run()
    in_compiled = dict(calls)
    reference.run()
    assert reference.steps == calls["decide"] - in_compiled["decide"]  # the reference decides every step
    assert in_compiled["decide"] == 0  # never the phases
    assert 0 < in_compiled["decide_tracked"] < compiled.steps  # agents acting
    assert in_compiled["movers_command"] > in_compiled["decide_tracked"]  # quiet steps that steer triangle routers
    assert np.count_nonzero(compiled.swarm.state == State.TRIANGLE_SETTLED) > 0
    np.testing.assert_array_equal(compiled.swarm.xy, reference.swarm.xy)
    np.testing.assert_array_equal(compiled.swarm.state, reference.swarm.state)


def test_routers_of_the_agents_model_that_drive_take_the_phases(monkeypatch):
    """Triangle routers of the agents' own model: the steps they drive in go phase by phase; the runs agree."""
    calls = _count_calls(monkeypatch, ("decide",))
    sc = load_scenario("agent-assisted-office-4bs", {"sim.time_limit": 120, "agents.per_base": 1,
                                                     "routers.robot": "pioneer"})
    compiled, reference = Simulation(sc, 3), Simulation(sc, 3, step="reference")
    compiled.run()
    in_compiled = calls["decide"]
    reference.run()
    assert 0 < in_compiled < compiled.steps
    np.testing.assert_array_equal(compiled.swarm.xy, reference.swarm.xy)
    np.testing.assert_array_equal(compiled.swarm.state, reference.swarm.state)


@pytest.mark.parametrize(("preset", "overrides"), [
    ("self-spreading-office", {"sim.time_limit": 60, "algorithm.params.triangular": "global"}),
    ("self-spreading-office", {"sim.time_limit": 60, "algorithm.params.walk": "growth"}),
    ("self-spreading-obstacles-6x6", {"sim.time_limit": 40, "algorithm.params.walk": "guided",
                                      "algorithm.params.stop_rule": "link-quality"}),
    ("potential-field-obstacles-6x6", {"sim.time_limit": 30}),
])
def test_batched_runs_are_the_same_with_either_step(preset, overrides):
    sc = load_scenario(preset, overrides)
    seeds = (1, 2, 3)
    compiled = BatchSimulation(sc, seeds)
    reference = BatchSimulation(sc, seeds, step="reference")
    assert compiled.compiled is not None and reference.compiled is None
    for a, b in zip(compiled.run(), reference.run(), strict=True):
        assert a.network == b.network
        for k in a.timeseries:
            np.testing.assert_array_equal(a.timeseries[k], b.timeseries[k])
    np.testing.assert_array_equal(compiled.swarm.xy, reference.swarm.xy)


@pytest.mark.parametrize("overrides", [
    {"algorithm.params.walk": "external"},
    {"algorithm.params.stop_rule": "external"},
])
def test_rules_it_does_not_compile_take_the_reference_path(overrides):
    sim = Simulation(load_scenario("self-spreading-6x6", {"sim.time_limit": 5, **overrides}), 1)
    assert sim.compiled is None and "sense" in sim.phase_seconds
    assert not CompiledSpreading.applies(sim.controller, sim.step_context())


def test_each_algorithm_gets_its_compiled_step_or_none():
    kinds = {preset: type(Simulation(load_scenario(preset, {"sim.time_limit": 5}), 1).compiled)
             for preset in ("self-spreading-6x6", "potential-field-6x6", "dssa-6x6", "agent-assisted-office")}
    assert kinds == {"self-spreading-6x6": CompiledSpreading, "potential-field-6x6": CompiledField,
                     "dssa-6x6": type(None), "agent-assisted-office": CompiledAgents}


def test_agent_runs_with_repair_take_the_compiled_step():  # (bit for bit: tests/test_compiled_repair.py)
    sc = load_scenario("agent-assisted-office", {"sim.time_limit": 5, "algorithm.params.repair": "relocate"})
    sim = Simulation(sc, 1)
    assert isinstance(sim.compiled, CompiledAgents) and sim.compiled.repair is not None


def test_an_unknown_step_kind_is_refused():
    with pytest.raises(ValueError, match="step must be"):
        Simulation(load_scenario("self-spreading-6x6"), 1, step="fast")


THREADED_CASES = {
    "triangle routers": ("self-spreading-office", 2, {"sim.time_limit": 150, "algorithm.params.triangular": "none"}),
    **{name: CASES[name] for name in ("office, two bases, local rule", "obstacles, global rule",
                                      "base station by a wall", "no body collisions", "walk growth, office, two bases",
                                      "walk guided, obstacles, global rule", "walk straight, hospital floor plan",
                                      "link-quality stop rule")},
}


@pytest.mark.parametrize("name", sorted(THREADED_CASES))
def test_the_threaded_step_gives_the_reference_run_bit_for_bit(name, threaded_spreading_calls):
    """Large runs (amronet.threads) sense, decide and plan on several threads, then move one by one: the same run."""
    calls = threaded_spreading_calls
    preset, seed, overrides = THREADED_CASES[name]
    sc = load_scenario(preset, overrides)
    fast, reference = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    fast.run()
    reference.run()
    assert len(calls) > 0
    for x, y in zip(_state(fast) + _walkers_memory(fast), _state(reference) + _walkers_memory(reference), strict=True):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(fast.controller.refused, reference.controller.refused)
    assert fast.rows == reference.rows
    if name == "triangle routers":
        assert np.count_nonzero(fast.swarm.state == State.TRIANGLE_SETTLED) > 0  # triangle routers steered too


def test_threaded_batches_are_the_same_as_serial_ones(monkeypatch):
    sc = load_scenario("self-spreading-office", {"sim.time_limit": 60, "algorithm.params.triangular": "global"})
    serial = BatchSimulation(sc, (1, 2, 3))
    serial_results = serial.run()
    monkeypatch.setattr(compiled_step, "use_threads", lambda n: True)
    threaded = BatchSimulation(sc, (1, 2, 3))
    for a, b in zip(threaded.run(), serial_results, strict=True):
        assert a.network == b.network
        for k in a.timeseries:
            np.testing.assert_array_equal(a.timeseries[k], b.timeseries[k])
    np.testing.assert_array_equal(threaded.swarm.xy, serial.swarm.xy)
