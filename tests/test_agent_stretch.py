"""Quiet stretches of agent-assisted runs (amronet.algorithms.agent_assisted.stretch) against the same runs step by
step."""

import ast
import inspect
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.algorithms.agent_assisted import (
    kernels,
    rule_kernels,
    stretch_books,
    stretch_kernels,
    stretch_links,
    stretch_tuples,
)
from amronet.algorithms.agent_assisted.controller import _pair_key
from amronet.algorithms.agent_assisted.explorers.frontier import knowledge, planning
from amronet.algorithms.agent_assisted.stretch import QuietStretch
from amronet.algorithms.agent_assisted.stretch_kernels import TRIANGLES_LOCAL, TRIANGLES_NONE, triangle_goes
from amronet.algorithms.common.triangular import select_triangles
from amronet.algorithms.stepping import RESTORING_AGENTS, AgentBooks
from amronet.engine.kernel_data import Csr, Grid
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.radio import NeighbourTable
from amronet.experiments.failures import _scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation

FRONTIER = {"algorithm.params.explorer": "frontier"}
SMALL = {**FRONTIER, "map": "cave", "radio.r_c": 4.0, "sim.time_limit": 150, "sim.coverage_target": "off",
         "base_stations": [{"x": 0.0, "y": 0.0, "region": [1.6, 1.6]}]}
"""A small map the agents explore in a minute, and a run that goes on: most steps with agents without a plan."""
FAILURES = {k: v for k, v in _scenario("agent-assisted", "office-32x32", 0.2, 600.0, 600.0, "frontier").items()
            if k != "faults"}
"""``reproduce failures``' agent-assisted run without its faults."""
FAULTS = {"sim.time_limit": 260, "faults": [{"at": 100.0, "routers": 0.3}, {"at": 101.05, "ids": [3]},
                                             {"rate_per_hour": 30.0, "at": 200.0}]}
"""Faults in the failures' run: stretches until the first, none after it (its damage is never repaired)."""
CASES = {
    "office, r_c 4 m": ("agent-assisted-office", 2, {**FRONTIER, "sim.time_limit": 300, "radio.r_c": 4.0}),
    "open floor, four agents": ("agent-assisted-office", 3, {**FRONTIER, "sim.time_limit": 200, "map": "open-32x32",
                                                             "agents.per_base": 4, "radio.r_c": 8.0}),
    "four bases, triangles": ("agent-assisted-office-4bs", 4, {**FRONTIER, "sim.time_limit": 150,
                                                               "agents.per_base": 1}),
    "no body collisions": ("agent-assisted-office", 5, {**FRONTIER, "sim.time_limit": 200,
                                                        "sim.robot_collisions": False}),
    "hospital floor plan, base by two walls": ("agent-assisted-office", 6, {
        **FRONTIER, "sim.time_limit": 200, "map": "hospital_section", "radio.r_c": 3.0,
        "base_stations": [{"x": 24.8555, "y": 3.4865, "region": [1.6, 1.6]}]}),
    "small map, agents idle, unit disk": ("agent-assisted-office", 7, SMALL),
    "small map, agents idle, multi-wall": ("agent-assisted-office", 8, {**SMALL, "radio.model": "multi-wall"}),
    "failures' run, no coverage target, agents idle": (FAILURES, 9, {"sim.time_limit": 900}),
    "failures' run with faults": (FAILURES, 10, FAULTS),
}


def _books(sim):
    sw, c, run = sim.swarm, sim.controller, sim.books
    ex = c.explorer
    links = run.agent_links
    return {"xy": sw.xy, "heading": sw.heading, "state": sw.state, "status": sw.status, "distance": sw.distance,
            "current": c.current, "left": c.left, "refused": c.refused, "nearest": c.nearest_d, "score": ex.grid.score,
            "seen": ex.grid.seen, "visited": ex.visited, "goal": ex.plans.goal, "path": ex.plans.path,
            "connected": links.connected_steps, "outages": links.outages, "longest": links.longest_outage_steps,
            "rng": np.frombuffer(json.dumps(c.rng.bit_generator.state).encode(), dtype=np.uint8),
            "table": sim.table.indices, "table_dist": sim.table.dist,
            "numbers": np.array([sim.steps, ex.steps, ex.grid.stamp, run.agents_connected_steps,
                                 run.agents_connected_sum, run.agents_connected_min, links.steps,
                                 links.all_connected_steps])}


def _summary(result):
    return json.dumps({k: v for k, v in result.summary.items() if k != "wall_time_s"}, sort_keys=True, default=float)


@pytest.mark.parametrize("name", sorted(CASES))
def test_stretches_give_the_step_by_step_run_bit_for_bit(name):
    preset, seed, overrides = CASES[name]
    sc = load_scenario(preset, overrides)
    fast, slow = Simulation(sc, seed), Simulation(sc, seed)
    assert isinstance(fast.compiled.quiet, QuietStretch)
    slow.compiled.quiet = None
    a, b = fast.run(), slow.run()
    for key, value in _books(slow).items():
        np.testing.assert_array_equal(_books(fast)[key], value, err_msg=key)
    assert fast.rows == slow.rows
    assert _summary(a) == _summary(b)
    ends = fast.compiled.quiet.ends
    assert sum(ends.values()) > 0  # stretches ran
    if "faults" in overrides:  # before the first fault only, and up to the step before it
        assert fast.books.fault_book.events[0].t == 100.0
        assert fast.compiled.quiet.ends["quiet"] > 0 and a.summary["faults"]["nodes_failed"] > 0
    if name == "office, r_c 4 m":  # whole stretches, and stretches that stopped where an agent acted
        assert ends["quiet"] > 0 and ends["acts"] > 0
    if name.startswith("hospital") or "idle" in name:  # the agents soon run out of plans: stretches go on with those
        assert fast.compiled.quiet.idle_steps > 0  # that walk at random
    if name.startswith("four bases"):  # steps where an agent heard another network and the local rule said no
        assert fast.compiled.quiet.triangles_looked_at > 0
        assert fast.controller.triangles_released  # and triangles that went ahead, in Python
        # triangle routers driving to their goals in stretches, and stretches that stopped where one arrived
        assert fast.compiled.quiet.triangle_steps > 0 and ends["triangle"] > 0


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["none", "local"]))
def test_the_kernels_triangle_rule_is_select_triangles(seed, rule):
    # what AgentAssisted.decide_tracked does with the candidates, against the stretch kernel's yes/no
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(4, 12)), int(rng.integers(1, 4))
    xy = rng.uniform(0.0, 10.0, (n + m, 2))
    if rng.random() < 0.5:  # references exactly r_c apart
        xy[1] = xy[0] + np.array([3.0, 0.0])
    agents = np.arange(n, n + m)
    current = np.full(n + m, -1, dtype=np.int64)
    current[agents] = rng.integers(0, n, m)
    other = rng.integers(-1, n, m)
    other[other == current[agents]] = -1
    left = rng.integers(0, 3, n + m)
    disabled = rng.random(n + m) < 0.5
    served = {_pair_key(int(agents[k]), int(current[agents[k]]), int(other[k])) for k in range(m)
              if other[k] >= 0 and rng.random() < 0.3}
    cand = np.flatnonzero((other >= 0) & (left[agents] >= 1))
    cand = cand[np.array([_pair_key(int(agents[k]), int(current[agents[k]]), int(other[k])) not in served
                          for k in cand], dtype=bool)]
    indptr, indices, dist = neighbour_csr(xy, 3.0)
    table = NeighbourTable(xy=xy, r=3.0, indptr=indptr, indices=indices, dist=dist)  # (read by the global rule only)
    expected = select_triangles(rule, agents[cand], current[agents][cand], other[cand], xy, 3.0, disabled, table,
                                np.ones(n + m, dtype=bool)).any()
    code = TRIANGLES_NONE if rule == "none" else TRIANGLES_LOCAL
    served_rows = np.array(sorted(served), dtype=np.int64).reshape(-1, 3)
    assert triangle_goes((code, 3.0, disabled, served_rows), agents, current, other, left, xy) == expected


def test_steps_stepped_one_by_one_take_no_stretch():
    sim = Simulation(load_scenario("agent-assisted-office", {**FRONTIER, "sim.time_limit": 30}), 1)
    for _ in range(20):
        sim.step()
    assert sum(sim.compiled.quiet.ends.values()) == 0


@pytest.mark.parametrize("overrides", [
    {"algorithm.params.explorer": "random"},  # the paper's explorer steers in Python
    {**FRONTIER, "radio.model": "multi-wall", "radio.packet_loss": True},  # links lost at random: the radio's own
])
def test_runs_it_cannot_take_in_stretches_have_none(overrides):
    sim = Simulation(load_scenario("agent-assisted-office", overrides), 1)
    assert sim.compiled is not None and sim.compiled.quiet is None


def test_a_recorded_run_is_stepped_one_by_one_to_the_same_end():
    from amronet.outputs.recording import Recorder

    sc = load_scenario("agent-assisted-office", {**FRONTIER, "sim.time_limit": 60})
    recorded, plain = Simulation(sc, 1), Simulation(sc, 1)
    recorded.run(recorder=Recorder(every=10))
    plain.run()
    assert sum(recorded.compiled.quiet.ends.values()) == 0 and sum(plain.compiled.quiet.ends.values()) > 0
    for key, value in _books(plain).items():
        np.testing.assert_array_equal(_books(recorded)[key], value, err_msg=key)


K, S, R, T = kernels, stretch_kernels, rule_kernels, stretch_tuples
UNPACKED = {  # (module, kernel): {tuple it unpacks: the named structure laid out in it}
    (K, "sense_track_agents"): {"grid": Grid, "robots": K.Robots, "ring": K.Ring, "near": Csr,
                                "tracking": K.Tracking, "table": Csr},
    (K, "integrate_agents"): {"robots": K.Robots, "ring": K.Ring, "knowledge": K.Knowledge},
    (K, "drive_movers"): {"robots": K.Robots},
    (S, "quiet_stretch"): {"grid": Grid, "robots": K.Robots, "ring": K.Ring, "moves": T.Moves, "radio": S.Radio,
                           "tracking": K.Tracking, "moving": T.Moving, "knowledge": K.Knowledge,
                           "cells": knowledge.Cells, "frontier": T.Frontier, "rules": R.RuleStep},
    (S, "triangle_goes"): {"triangles": T.Triangles},
    (R, "rule_quiet"): {"books": R.RuleBooks, "inputs": R.RuleInputs},
    (R, "rule_commit"): {"books": R.RuleBooks},
    (R, "rule_acts"): {"rules": R.RuleStep},
    (stretch_books, "observe_links"): {"books": AgentBooks, "arrays": stretch_books.Links},
    (stretch_books, "back_up_starts"): {"reverse_drop": stretch_books.ReverseDrop},
    (stretch_books, "back_up"): {"reverse_drop": stretch_books.ReverseDrop},
    (stretch_links, "next_radio"): {"radio": stretch_links.Radio},
    (knowledge, "integrate_readings"): {"cells": knowledge.Cells},
    (planning, "search_target"): {"targets": planning.Targets, "claims": planning.Claims},
}


@pytest.mark.parametrize(("module", "name"), list(UNPACKED), ids=lambda v: getattr(v, "__name__", v))
def test_the_kernels_unpack_their_named_structures_in_the_order_of_their_fields(module, name):
    # callers hand the named structures over as plain tuples, which the kernels unpack by position: each name unpacked
    # is the field's, with a prefix of its own, or "_" (unused)
    kernel = next(node for node in ast.parse(inspect.getsource(module)).body
                  if isinstance(node, ast.FunctionDef) and node.name == name)
    unpacked = {stmt.value.id: [target.id for target in stmt.targets[0].elts] for stmt in ast.walk(kernel)
                if isinstance(stmt, ast.Assign) and isinstance(stmt.targets[0], ast.Tuple)
                and isinstance(stmt.value, ast.Name) and stmt.value.id in UNPACKED[module, name]}
    assert set(unpacked) == set(UNPACKED[module, name])
    for source, names in unpacked.items():
        fields = UNPACKED[module, name][source]._fields
        assert len(names) == len(fields), source
        for got, field in zip(names, fields, strict=True):
            assert got in ("_", field) or got.endswith("_" + field), (source, got, field)


def test_a_stretch_until_the_agents_are_linked_stops_after_the_first_step_they_all_are(monkeypatch):
    # what the loop may ask while a fault's damage waits for the agents only: every stretch asked so, the same run
    ended = []

    def until_linked(self, limit, now, books, silent=None, restoring=0, take=QuietStretch.take):
        before = int(books.arrays[5][1])  # (steps with every agent linked)
        out = take(self, limit, now, books, silent, RESTORING_AGENTS)
        if out is not None:
            ended.append((int(books.arrays[5][1]) - before, bool(books.arrays[0].all()), out.finish is None))
        return out

    monkeypatch.setattr(QuietStretch, "take", until_linked)
    sc = load_scenario("agent-assisted-office", {**FRONTIER, "agents.routers_carried": 2, "sim.time_limit": 150,
                                                 "agents.when_empty": "continue", "sim.coverage_target": "off"})
    fast, slow = Simulation(sc, 2), Simulation(sc, 2)
    slow.compiled.quiet = None
    a, b = fast.run(), slow.run()
    for key, value in _books(slow).items():
        np.testing.assert_array_equal(_books(fast)[key], value, err_msg=key)
    assert _summary(a) == _summary(b)
    ends = fast.compiled.quiet.ends
    assert ends["linked"] > 0 and ends["quiet"] > 0  # (and stretches with an agent out of contact all along)
    linked = [e for e in ended if e[0]]
    assert len(linked) == ends["linked"]  # a stretch stops at the first step after which every agent is linked
    assert all(e == (1, True, True) for e in linked)
