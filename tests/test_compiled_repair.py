"""Runs that repair (``repair: relocate``, ``retrace``) take the compiled step and quiet stretches, bit for bit.

Each case runs once with the compiled step (stretches before the fault, compiled steps after it, the controller's own
code where the repair acts) and once phase by phase (``step="reference"``), and compares the robots, the controller's
and the repair's arrays, the table, the summary (its ``faults`` and ``mission`` too), the time series and the records.
The faults cut the network: routers relocate or back up their way, and under ``retrace`` agents back up theirs;
stretches take steps in which they do (counted).
Once the damage is repaired, stretches go on with the failed nodes silent (``AFTER_FAULT``), with a repair or without.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.algorithms.agent_assisted.fast import CompiledAgents
from amronet.algorithms.agent_assisted.retrace import Breadcrumbs, Retracer
from amronet.algorithms.agent_assisted.stretch import QuietStretch
from amronet.algorithms.stepping import RESTORING_AGENTS, RESTORING_ROUTERS
from amronet.experiments.failures import _scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from test_repair_retrace import DROPS, END, scenario, two_rooms

FAULT_AT, AFTER, FRACTION, SEED = 100.0, 150.0, 0.3, 5

CASES = {  # name: (scenario, seed, whether an agent backs up)
    "relocate office unit-disk": (("agent-assisted-relocate", "office-32x32", "unit-disk"), SEED, False),
    "retrace office unit-disk": (("agent-assisted-retrace", "office-32x32", "unit-disk"), SEED, True),
    "relocate office multi-wall shadowing": (("agent-assisted-relocate", "office-32x32", "multi-wall-shadowing"),
                                             SEED, False),
    "relocate hospital multi-wall": (("agent-assisted-relocate", "hospital_section", "multi-wall"), SEED, False),
    "retrace hospital multi-wall": (("agent-assisted-retrace", "hospital_section", "multi-wall"), SEED, True),
    "retrace hospital multi-wall shadowing": (("agent-assisted-retrace", "hospital_section", "multi-wall-shadowing"),
                                              SEED, True),
    # no fault, agents that go on without routers: they lose contact and back up, in the steps a stretch would take
    "retrace agents out of contact": ({"algorithm.params.explorer": "frontier", "algorithm.params.repair": "retrace",
                                       "agents.routers_carried": 2, "agents.when_empty": "continue",
                                       "sim.time_limit": 150, "sim.coverage_target": "off"}, 2, True),
}



def _failures(algorithm, map_name, radio, at=300.0, faults=None):
    """The failures' run: a fifth of the deployed routers fail at ``at``, and as long again after (or ``faults``)."""
    sc = _scenario(algorithm, map_name, 0.2, at, at, "frontier", radio)
    return sc if faults is None else {**sc, "faults": faults}


REFERENCE_FAILS = (300.0, 1, 30)
"""At that time agent 1's current reference is router 30 (seed 3 of the office's run without repair)."""
AFTER_FAULT = {  # name: (scenario, seed): the fault's damage is repaired, then stretches take steps, the failed silent
    "no repair office multi-wall shadowing": (_failures("agent-assisted", "office-32x32", "multi-wall-shadowing"), 1),
    "no repair office, an agent's reference fails, the agent is spared": (_failures(
        "agent-assisted", "office-32x32", "unit-disk", faults=[{"at": REFERENCE_FAILS[0], "ids": [1, 30]}]), 3),
    "no repair, four bases, triangles, a base station fails": (("agent-assisted-office-4bs", {
        "algorithm.params.explorer": "frontier", "sim.time_limit": 300, "agents.per_base": 1,
        "faults": [{"at": 100.0, "base_station": 1}]}), 4),
    "relocate office unit-disk": (_failures("agent-assisted-relocate", "office-32x32", "unit-disk", 600.0), 2),
    "relocate office multi-wall shadowing": (_failures("agent-assisted-relocate", "office-32x32",
                                                       "multi-wall-shadowing"), 5),
    "retrace office unit-disk": (_failures("agent-assisted-retrace", "office-32x32", "unit-disk"), 5),
    "retrace hospital multi-wall": (_failures("agent-assisted-retrace", "hospital_section", "multi-wall", 600.0), 1),
    "retrace hospital multi-wall shadowing": (_failures("agent-assisted-retrace", "hospital_section",
                                                        "multi-wall-shadowing"), 2),
}


def _load(source):
    if isinstance(source, dict) and "algorithm" in source:  # a whole scenario
        return load_scenario(source)
    if isinstance(source, dict):
        return load_scenario("agent-assisted-office", source)
    if isinstance(source[1], dict):  # a preset and its overrides
        return load_scenario(*source)
    return load_scenario(_scenario(source[0], source[1], FRACTION, FAULT_AT, AFTER, "frontier", source[2]))


def _books(sim) -> dict[str, np.ndarray]:
    sw, c = sim.swarm, sim.controller
    r, links = c.relocator, sim.books.agent_links
    out = {"xy": sw.xy, "heading": sw.heading, "state": sw.state, "status": sw.status, "distance": sw.distance,
           "current": c.current, "left": c.left, "refused": c.refused, "released_by": c.released_by,
           "nearest": c.nearest_d, "disabled": c.disabled,
           "rng": np.frombuffer(json.dumps(c.rng.bit_generator.state).encode(), dtype=np.uint8),
           "table": sim.table.indices, "table_dist": sim.table.dist, "table_indptr": sim.table.indptr,
           "geometric": sim.table.geometric.indices, "connected": links.connected_steps, "outages": links.outages,
           "longest": links.longest_outage_steps, "numbers": np.array([sim.steps, links.all_connected_steps])}
    if r is not None:
        out.update({"losses": r._li, "lost": r._lj, "since": r._since, "where": r._where, "pairs": r._pairs,
                    "goal": r.steering.goal, "blocked": r.steering.blocked_steps, "to_goal": r.steering.last_to_goal,
                    "repair": np.array([r.moves, r.n])})
    if hasattr(c.explorer, "grid"):
        out["score"] = c.explorer.grid.score
    if isinstance(r, Retracer):
        k = r.crumbs.count
        out.update({"node": r.node, "skips": r.skips, "backing": r.backing, "contact_at": r.contact_at,
                    "crumbs": r.crumbs.xy[:k], "parents": r.crumbs.parent[:k], "tips": r.crumbs.tip,
                    "paths": np.concatenate(r.crumbs.paths), "counts": np.array([r.skipped, r.agent_backs, k])})
    return out


def _summary(result) -> str:
    return json.dumps({k: v for k, v in result.summary.items() if k != "wall_time_s"}, sort_keys=True, default=repr)


def _assert_same(fast, slow, a, b):
    """The compiled run ``fast`` (result ``a``) and the reference ``slow`` (``b``) end the same, bit for bit."""
    for key, value in _books(slow).items():
        np.testing.assert_array_equal(_books(fast)[key], value, err_msg=key)
    assert _summary(a) == _summary(b)
    assert a.timeseries.keys() == b.timeseries.keys()
    for key, series in b.timeseries.items():
        np.testing.assert_array_equal(a.timeseries[key], series, err_msg=key)
    assert fast.rows == slow.rows and a.network == b.network


@pytest.fixture
def stretches(monkeypatch):
    """``(t, steps, silent, restoring)`` of every stretch a quiet stretch was asked for (``silent``: failed nodes
    were given; ``restoring``: what it was told of a fault's damage not repaired yet)."""
    noted = []

    def noting(self, limit, now, books, silent=None, restoring=0, take=QuietStretch.take):
        out = take(self, limit, now, books, silent, restoring)
        noted.append((now.t, 0 if out is None else out.steps, silent is not None, restoring))
        return out

    monkeypatch.setattr(QuietStretch, "take", noting)
    return noted


@pytest.mark.parametrize("name", sorted(CASES))
def test_repairing_runs_take_the_compiled_step_bit_for_bit(name):
    source, seed, backs = CASES[name]
    sc = _load(source)
    fast, slow = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    assert isinstance(fast.compiled, CompiledAgents) and fast.compiled.repair is not None
    a, b = fast.run(), slow.run()
    _assert_same(fast, slow, a, b)
    relocator = fast.controller.relocator
    if isinstance(source, tuple):  # the fault cut routers off, and they moved
        assert a.summary["faults"] and a.summary["mission"]["relocations"] > 0
    assert (relocator.agent_backs > 0) == backs if isinstance(relocator, Retracer) else not backs
    repair = fast.compiled.repair
    if isinstance(source, tuple):  # routers relocated (or retraced their way) in stretches too
        assert repair.relocating_steps > 0
    assert (repair.backing_steps > 0) == backs  # and agents backed up their own in stretches
    # stretches took steps, and the idle relocator's update was left out in them and in compiled steps
    assert sum(fast.compiled.quiet.ends.values()) > 0
    assert fast.compiled.repair.updates_skipped > fast.steps / 4


@pytest.mark.parametrize("name", sorted(AFTER_FAULT))
def test_stretches_go_on_after_the_fault_with_the_failed_nodes_silent(name, stretches):
    """Stretches after the fault drop the failed nodes' links from every table their kernel builds, bit for bit."""
    source, seed = AFTER_FAULT[name]
    sc = _load(source)
    if "reference fails" in name:  # the router that fails is the agent's reference then
        probe = Simulation(sc, seed)
        t, agent, router = REFERENCE_FAILS
        while probe.t < t - 1e-9:
            probe.step()
        assert probe.controller.current[agent] == router
    fast, slow = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    a = fast.run()
    taken = [(t, steps, silent) for t, steps, silent, _ in stretches if steps]
    b = slow.run()
    _assert_same(fast, slow, a, b)
    events = a.summary["faults"]["events"]
    first = events[0]["t"]
    assert all(e["restored_after_s"] is not None for e in events)  # the damage was repaired: the loop offers stretches
    assert all(silent == (t > first) for t, _, silent in taken)
    assert sum(steps for t, steps, _ in taken if t > first) > 0  # (none before the failed nodes were silenced)
    if "spared" in name:  # the agent named in the fault cannot fail: only its reference did
        assert a.summary["faults"]["nodes_failed"] == 1 and a.summary["faults"]["skipped"]
    if "base station" in name:
        assert [e["kind"] for e in events] == ["base_station"]


WAITING = {  # name: (scenario, seed, what the stretches are told of the damage while it waits to be repaired)
    "no repair office, repaired late": (("agent-assisted", "office-32x32", "unit-disk"), 1, RESTORING_ROUTERS),
    "no repair hospital, repaired by a router put down": (("agent-assisted", "hospital_section", "unit-disk"), 2,
                                                          RESTORING_ROUTERS),
    "relocate office, the agents reconnect last": (("agent-assisted-relocate", "office-32x32", "unit-disk"), 3,
                                                   RESTORING_AGENTS),
}


@pytest.mark.parametrize("name", sorted(WAITING))
def test_stretches_go_on_while_the_damage_waits_to_be_repaired(name, stretches):
    """A cut-off router with no relay moving cannot get its path back in a stretch; cut-off agents stop it once
    they all have one: the faults' books see every step they would see step by step."""
    source, seed, restoring = WAITING[name]
    sc = _load(source)
    fast, slow = Simulation(sc, seed), Simulation(sc, seed, step="reference")
    a, b = fast.run(), slow.run()
    _assert_same(fast, slow, a, b)
    assert a.summary["faults"]["events"][0]["restored_after_s"] > 0  # (restored in a step the books saw)
    assert sum(steps for _, steps, _, told in stretches if told == restoring) > 0
    if restoring == RESTORING_AGENTS:  # a stretch stopped after the step at whose end the agents all had a path
        assert fast.compiled.quiet.ends["linked"] > 0


def test_routers_put_down_between_steps_are_watched_from_the_next_table(tmp_path):
    """Routers put down by hand between two steps (the two-room case): the step's table does not have them yet."""
    sims = [Simulation(scenario(tmp_path, "retrace"), seed=1, omap=two_rooms(), step=step)
            for step in ("compiled", "reference")]
    for sim in sims:
        placed: list[int] = []
        while sim.t < END - 1e-9:
            if any(abs(sim.t - t) < 1e-9 for t in DROPS):
                placed.append(sim.controller._release_reference(int(sim.agents[0]),
                                                                placed[-1] if placed else int(sim.bases[0]), sim.t))
            sim.step()
    fast, slow = sims
    assert fast.controller.relocator.moves == 1 and fast.compiled.repair.updates_skipped > 0
    for key, value in _books(slow).items():
        np.testing.assert_array_equal(_books(fast)[key], value, err_msg=key)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(1, 3))
def test_breadcrumbs_replay_records_step_by_step(seed, steps, agents):
    """A stretch's odometry, replayed from the positions it hands back, is what recording each step gives."""
    rng = np.random.default_rng(seed)
    start = rng.uniform(0, 5, (agents, 2))
    trail = start + np.cumsum(rng.normal(0, 0.15, (steps, agents, 2)), axis=0)
    one, other = Breadcrumbs(start, 0.3, 0.4), Breadcrumbs(start, 0.3, 0.4)
    for s in range(steps):
        one.record(trail[s], np.ones(agents, dtype=bool))
    other.replay(trail)
    assert one.count == other.count
    np.testing.assert_array_equal(one.xy[:one.count], other.xy[:other.count])
    np.testing.assert_array_equal(one.parent[:one.count], other.parent[:other.count])
    np.testing.assert_array_equal(one.tip, other.tip)
    for x, y in zip(one.paths, other.paths, strict=True):
        np.testing.assert_array_equal(x, y)
