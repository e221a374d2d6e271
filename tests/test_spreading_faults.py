"""Self-spreading and potential-field runs with faults: the compiled step (and its stretches, before the first fault
and, for self-spreading, after it) against the phases one by one (``step="reference"``), bit for bit."""

import json

import numpy as np
import pytest

from amronet.algorithms.potential_field.fast import CompiledField
from amronet.algorithms.self_spreading.fast import CompiledSpreading
from amronet.engine.robots import State
from amronet.experiments.failures import _scenario
from amronet.experiments.walks import walk_scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.faults import FaultSchedule

GO_ON = {"sim.stop_when_settled": False}
CASES = {
    # router 73 drives to its triangle goal from 133.8 s to 136.3 s, router 5 still explores at 135 s
    "office: a triangle router and an explorer fail, then a base station": ("self-spreading-office", 2, {
        **GO_ON, "sim.time_limit": 170, "faults": [{"at": 135.0, "ids": [73, 5]}, {"at": 150.0, "base_station": 1}]}),
    "office, link-quality triangle rule: triangle routers search by the phases": ("self-spreading-office", 2, {
        **GO_ON, "sim.time_limit": 175, "algorithm.params.triangular": "none",
        "algorithm.params.triangle_rule": "link-quality",  # (router 73 searches from 146.7 s to 147.7 s)
        "faults": [{"at": 147.0, "ids": [73, 5]}, {"at": 155.0, "base_station": 1}]}),
    "office: Poisson failures": ("self-spreading-office", 5, {
        **GO_ON, "sim.time_limit": 130, "faults": [{"rate_per_hour": 50.0, "at": 40.0}]}),
    "office, global rule: a triangle starts between two faults": ("self-spreading-office", 4, {
        **GO_ON, "sim.time_limit": 110, "algorithm.params.triangular": "global",
        "faults": [{"at": 97.0, "ids": [7, 8]}, {"at": 105.0, "routers": 0.3}]}),
    "reproduce failures' autolab run, shortened": (_scenario("self-spreading", "autolab", 0.3, 60.0, 60.0, "frontier"),
                                                    2, {}),
    "reproduce failures' office run, shortened": (_scenario("self-spreading", "office-32x32", 0.2, 50.0, 30.0,
                                                            "frontier"), 1, {}),
    "hospital floor plan: explorers fail, then a fraction and the base": (
        walk_scenario("hospital_section", "random", 60.0), 80_000, {
            **GO_ON, "faults": [{"at": 15.0, "ids": [2, 3, 9]}, {"at": 40.0, "routers": 0.3},
                                {"at": 50.0, "base_station": 0}]}),
    "office, growth walk": ("self-spreading-office", 2, {
        **GO_ON, "sim.time_limit": 80, "algorithm.params.walk": "growth", "algorithm.params.triangular": "none",
        "faults": [{"at": 15.0, "ids": [6, 9]}, {"at": 50.0, "routers": 0.3}]}),
    "office, link-quality stop rule": ("self-spreading-office", 2, {
        **GO_ON, "sim.time_limit": 80, "algorithm.params.stop_rule": "link-quality",
        "faults": [{"at": 15.0, "ids": [6, 9]}, {"at": 50.0, "routers": 0.3}]}),
    "office, multi-wall radio": ("self-spreading-office", 5, {
        **GO_ON, "sim.time_limit": 30, "radio.model": "multi-wall",
        "faults": [{"at": 10.0, "ids": [6, 9]}, {"at": 20.0, "routers": 0.5}]}),
    "office: an explorer fails, then Poisson failures start": ("self-spreading-office", 3, {
        **GO_ON, "sim.time_limit": 110, "faults": [{"at": 30.0, "ids": [4]}, {"rate_per_hour": 60.0, "at": 80.0}]}),
    "potential field": ("potential-field-obstacles-6x6", 2, {
        "sim.time_limit": 60, "faults": [{"at": 5.0, "ids": [3]}, {"at": 20.0, "routers": 0.3},
                                         {"rate_per_hour": 300.0, "at": 30.0}]}),
}
STRETCHED = {"office: a triangle router and an explorer fail, then a base station", "office: Poisson failures",
             "office, link-quality triangle rule: triangle routers search by the phases",
             "office, global rule: a triangle starts between two faults", "reproduce failures' autolab run, shortened",
             "reproduce failures' office run, shortened",
             "hospital floor plan: explorers fail, then a fraction and the base", "office, growth walk",
             "office: an explorer fails, then Poisson failures start", "potential field"}
"""The cases whose compiled step takes stretches until the first fault (the unit disk, the distance stop rule)."""
SILENCED = STRETCHED - {"office: Poisson failures", "potential field"}
"""Those whose compiled step takes stretches after the first fault too (self-spreading silences failed nodes): while
every fault's damage is repaired and none is due (a Poisson rate may strike in any step once it has started; the
potential field's forces count every neighbour, failed or not)."""
NEVER_RESTORED = {"hospital floor plan: explorers fail, then a fraction and the base": 50.0}
"""A base station fails at that time and the network never finds another: no stretch after it."""


def _books(sim):
    sw, c = sim.swarm, sim.controller
    arrays = [sw.xy, sw.heading, sw.state, sw.status, sw.distance, sim.table.indptr, sim.table.indices,
              sim.table.dist]
    for name in ("current", "disabled", "refused", "velocity", "rest_count", "window_start", "held_force", "wakeups"):
        if hasattr(c, name):
            arrays.append(getattr(c, name))
    if hasattr(c, "walker"):
        arrays += [c.walker.follow, c.walker.side, c.walker.deployed_at]
    if getattr(c, "smoother", None) is not None:
        arrays.append(c.smoother.value)
    if hasattr(c, "steering"):
        arrays += [c.steering.goal, c.steering.anchors]
    return arrays


def _summary(result):
    return json.dumps({k: v for k, v in result.summary.items() if k != "wall_time_s"}, sort_keys=True, default=float)


@pytest.fixture
def struck(monkeypatch):
    """``(t, kind, states of the nodes just before they fail)`` of every fault event of the runs in the test."""
    events = []
    due = FaultSchedule.due

    def noting(self, t, role, state, deployed):
        out = due(self, t, role, state, deployed)
        events.extend((round(t, 6), kind, state[ids].tolist()) for kind, ids in out)
        return out

    monkeypatch.setattr(FaultSchedule, "due", noting)
    return events


@pytest.fixture
def stretches(monkeypatch):
    """``(t, steps, silent, ends)`` of every stretch the compiled steps were offered (``ends``: how it ended)."""
    noted = []
    for cls in (CompiledSpreading, CompiledField):
        def noting(self, limit, now, watch, stretch=cls.stretch):
            before = dict(self.stretcher.ends) if self.stretcher is not None else {}
            out = stretch(self, limit, now, watch)
            after = dict(self.stretcher.ends) if self.stretcher is not None else {}
            ends = {k for k in after if after[k] != before[k]}
            noted.append((now.t, 0 if out is None else out.steps, watch.silent is not None, ends))
            return out

        monkeypatch.setattr(cls, "stretch", noting)
    return noted


def _assert_same(fast, reference, a, b):
    for x, y in zip(_books(fast), _books(reference), strict=True):
        np.testing.assert_array_equal(x, y)
    assert fast.rows == reference.rows and a.network == b.network and _summary(a) == _summary(b)
    assert a.timeseries.keys() == b.timeseries.keys()
    for k in a.timeseries:
        np.testing.assert_array_equal(a.timeseries[k], b.timeseries[k])
    assert fast.books.faults.skipped == reference.books.faults.skipped == []
    assert fast.books.fault_book.events == reference.books.fault_book.events


@pytest.mark.parametrize("name", sorted(CASES))
def test_runs_with_faults_take_the_compiled_step_bit_for_bit(name, struck, stretches):
    preset, seed, overrides = CASES[name]
    sc = load_scenario(preset, overrides)
    fast, reference = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    assert fast.compiled is not None and reference.compiled is None
    a = fast.run()
    compiled_events = list(struck)
    taken = [(t, steps, silent, ends) for t, steps, silent, ends in stretches if steps]
    b = reference.run()
    assert compiled_events and struck[len(compiled_events):] == compiled_events  # the same faults struck
    assert (fast.swarm.state == State.FAILED).any()
    _assert_same(fast, reference, a, b)
    stretcher = getattr(fast.compiled, "stretcher", None)
    if name in STRETCHED:  # until the first fault
        assert stretcher is not None and stretcher.steps > 0
    first = compiled_events[0][0]
    after = sum(steps for t, steps, _, _ in taken if t > first)
    assert all(silent == (t > first) for t, _, silent, _ in taken)
    if name in SILENCED:  # and after it, the failed nodes silent
        assert after > 0 and after == stretcher.silent_steps
    else:
        assert after == 0
    if name in NEVER_RESTORED:
        assert not [t for t, *_ in taken if t >= NEVER_RESTORED[name]]
        assert fast.books.fault_book.events[-1].restored_at is None
    if "Poisson failures start" in name:  # between the ids fault and the rate's start, not after
        assert {round(t) for t, *_ in taken if t > first} <= set(range(30, 80))
    if "global" in name:  # a triangle may start: a stretch after a fault ends before that step
        assert any(silent and ends == {"candidates"} for _, _, silent, ends in taken)
    if "triangle rout" in name:  # what the ids fault hit: an explorer and a triangle router
        assert any(e[1:] == ("ids", [State.EXPLORE, State.TRIANGLE]) for e in compiled_events)
    if name.startswith("hospital"):
        assert (15.0, "ids", [State.EXPLORE] * 3) in compiled_events
    if "triangle starts" in name or "growth" in name:
        assert (fast.swarm.state == State.TRIANGLE_SETTLED).any()


@pytest.mark.parametrize("name", ["office: a triangle router and an explorer fail, then a base station",
                                  "hospital floor plan: explorers fail, then a fraction and the base"])
def test_the_threaded_step_takes_runs_with_faults_bit_for_bit(name, threaded_spreading_calls):
    """Large runs (amronet.threads) sense, decide and plan on several threads: the same run with faults too."""
    calls = threaded_spreading_calls
    preset, seed, overrides = CASES[name]
    sc = load_scenario(preset, overrides)
    fast, reference = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    a, b = fast.run(), reference.run()
    assert len(calls) > 0
    _assert_same(fast, reference, a, b)


def test_a_failed_robot_never_moves_again_whatever_it_was_doing():
    preset, seed, overrides = CASES["office: a triangle router and an explorer fail, then a base station"]
    sim = Simulation(load_scenario(preset, overrides), seed)
    assert sim.compiled is not None
    sim.advance(1351)  # to the end of the fault's step (at 135 s)
    failed = np.flatnonzero(sim.swarm.state == State.FAILED)
    assert failed.tolist() == [5, 73]
    xy, heading, distance = sim.swarm.xy[failed].copy(), sim.swarm.heading[failed].copy(), sim.swarm.distance.copy()
    sim.run()
    np.testing.assert_array_equal(sim.swarm.xy[failed], xy)
    np.testing.assert_array_equal(sim.swarm.heading[failed], heading)
    np.testing.assert_array_equal(sim.swarm.distance[failed], distance[failed])
    assert (sim.swarm.distance > distance).any()  # the others went on
