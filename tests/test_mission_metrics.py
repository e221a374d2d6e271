"""Mission metrics (issue #19): per-agent connection, outages, relays used and distance in ``summary["mission"]``."""

from __future__ import annotations

import json

import numpy as np
import pytest

import amronet
from amronet.engine.network import agents_connected
from amronet.engine.robots import Role
from amronet.scenario import AgentsSpec, Scenario
from amronet.sim import Simulation
from amronet.sim.run import OutageTracker
from amronet.sweeps import ResultStore
from amronet.sweeps.plot import plot_groups
from amronet.sweeps.tables import run_rows
from amronet.sweeps.worker import execute_job
from helpers import open_field_agents

MISSION_KEYS = {"connected_fraction", "longest_outage_s", "outages", "time_all_connected_fraction", "relays_used",
                "relays_per_100m2_covered", "distance_travelled_m", "per_agent"}
PER_AGENT_KEYS = {"id", "connected_fraction", "longest_outage_s", "outages", "distance_m"}


def agent_scenario(**over: object) -> Scenario:
    """Agent-assisted deployment in an open field, two agents, short: under a second a run."""
    return open_field_agents(**{"sim.time_limit": 100.0, **over})


def cut_off_scenario() -> Scenario:
    """Agents that carry one router each and go on exploring when they have none left: they are cut off."""
    if "when_empty" not in AgentsSpec.model_fields:
        pytest.skip("agents.when_empty does not exist (yet): no scenario cuts agents off")
    return agent_scenario(**{"agents.routers_carried": 1, "agents.when_empty": "continue"})


def reference_outages(seq: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Per agent, by a plain loop: connected fraction, outages, longest outage in seconds; all-connected fraction."""
    steps, n = seq.shape
    outages = np.zeros(n, dtype=int)
    longest = np.zeros(n)
    for a in range(n):
        run = 0
        for k in range(steps):
            if seq[k, a]:
                run = 0
                continue
            if run == 0:
                outages[a] += 1
            run += 1
            longest[a] = max(longest[a], run * dt)
    return seq.mean(axis=0), outages, longest, float(seq.all(axis=1).mean())


# -- the bookkeeping ----------------------------------------------------------------------------------------------
def test_outage_tracker_counts_stretches_at_the_start_in_the_middle_and_at_the_end():
    seq = np.array([[c == "1" for c in row] for row in (
        "01",  # agent 0 cut off from the first step
        "01",
        "10",
        "11",
        "00",
        "01",
        "10",  # agent 1 cut off until the end: the outage is closed there
        "10",
        "10",
    )])
    tracker = OutageTracker(np.array([True, True]))
    for linked in seq:
        tracker.observe(linked)
    assert tracker.steps == 9
    assert tracker.outages.tolist() == [2, 3]
    assert tracker.longest_outage_steps.tolist() == [2, 3]
    assert tracker.connected_steps.tolist() == [5, 4]
    np.testing.assert_array_equal(tracker.connected_fraction, [5 / 9, 4 / 9])
    assert tracker.all_connected_fraction == 1 / 9
    fractions, outages, longest, everyone = reference_outages(seq, 1.0)
    np.testing.assert_array_equal(tracker.connected_fraction, fractions)
    np.testing.assert_array_equal(tracker.outages, outages)
    np.testing.assert_array_equal(tracker.longest_outage_steps, longest)
    assert tracker.all_connected_fraction == everyone


def test_outage_tracker_matches_a_plain_loop_on_random_sequences():
    rng = np.random.default_rng(7)
    for _ in range(50):
        steps, n = int(rng.integers(1, 40)), int(rng.integers(1, 5))
        seq = rng.random((steps, n)) < rng.uniform(0.2, 0.9)
        tracker = OutageTracker(rng.random(n) < 0.5)
        for linked in seq:
            tracker.observe(linked)
        fractions, outages, longest, everyone = reference_outages(seq, 1.0)
        np.testing.assert_allclose(tracker.connected_fraction, fractions, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(tracker.outages, outages)
        np.testing.assert_array_equal(tracker.longest_outage_steps, longest)
        assert tracker.all_connected_fraction == pytest.approx(everyone, abs=1e-15)


def test_outage_tracker_initial_state_counts_only_without_steps():
    initial = np.array([False, True])
    tracker = OutageTracker(initial)
    # no step: the initial state stands as the one observation, its outage lasted no time
    assert tracker.connected_fraction.tolist() == [0.0, 1.0]
    assert tracker.outages.tolist() == [1, 0]
    assert tracker.longest_outage_steps.tolist() == [0, 0]
    assert tracker.all_connected_fraction == 0.0
    # once a step is observed, the initial state is left out (as in agents_connected_fraction)
    tracker.observe(np.array([True, True]))
    assert tracker.connected_fraction.tolist() == [1.0, 1.0]
    assert tracker.outages.tolist() == [0, 0]
    assert tracker.all_connected_fraction == 1.0


# -- runs ---------------------------------------------------------------------------------------------------------
def check_mission(summary: dict) -> dict:
    """The invariants of a run's ``mission`` section; returns it."""
    m = summary["mission"]
    assert MISSION_KEYS <= set(m)
    assert set(m) - MISSION_KEYS <= {"drop_rule", "triangle_relays", "reverse_drops", "drops_by_cause",
                                     "triangle_relays_cut_off"}
    assert m["connected_fraction"] == summary["agents_connected_fraction"]
    per_agent = m["per_agent"]
    assert len(per_agent) == summary["agents"]
    assert [a["id"] for a in per_agent] == sorted(a["id"] for a in per_agent)
    for a in per_agent:
        assert PER_AGENT_KEYS <= set(a) <= PER_AGENT_KEYS | {"relays_dropped"}
        assert ("relays_dropped" in a) == (summary["algorithm"] == "agent-assisted")
        assert 0.0 <= a["connected_fraction"] <= 1.0
        assert 0.0 <= a["longest_outage_s"] <= summary["sim_time_s"]
        assert a["longest_outage_s"] == round(a["longest_outage_s"], 9)
    assert np.mean([a["connected_fraction"] for a in per_agent]) == pytest.approx(
        summary["agents_connected_fraction"], abs=1e-12)
    assert m["outages"] == sum(a["outages"] for a in per_agent)
    assert m["longest_outage_s"] == max(a["longest_outage_s"] for a in per_agent)
    assert m["distance_travelled_m"] == pytest.approx(sum(a["distance_m"] for a in per_agent), rel=1e-12)
    assert m["time_all_connected_fraction"] <= min(a["connected_fraction"] for a in per_agent) + 1e-12
    if summary["algorithm"] == "agent-assisted":  # every router was put down by an agent
        assert m["relays_used"] == summary["routers_total"]
        assert m["relays_used"] == sum(a["relays_dropped"] for a in per_agent)
    else:
        assert m["relays_used"] == summary["routers_deployed"]
    covered_m2 = summary["coverage"] * summary["reachable_area_m2"]
    assert m["relays_per_100m2_covered"] == pytest.approx(m["relays_used"] / (covered_m2 / 100), rel=1e-12)
    assert json.loads(json.dumps(m, allow_nan=False)) == m  # plain JSON: ints, floats, lists, dicts
    return m


def test_tethered_agents_have_no_outage():
    result = amronet.run(agent_scenario(**{"agents.routers_carried": 2}), seed=4)
    s = result.summary
    m = check_mission(s)
    assert m["connected_fraction"] == 1.0 and m["time_all_connected_fraction"] == 1.0
    assert m["outages"] == 0 and m["longest_outage_s"] == 0.0
    assert all(a["connected_fraction"] == 1.0 and a["outages"] == 0 for a in m["per_agent"])
    assert m["relays_used"] >= 1 and m["relays_used"] == s["routers_total"]  # every router was released by an agent
    sw = result.run.swarm
    agents = np.flatnonzero(sw.role == Role.AGENT)
    assert [a["id"] for a in m["per_agent"]] == agents.tolist()
    assert [a["distance_m"] for a in m["per_agent"]] == sw.distance[agents].tolist()
    assert m["distance_travelled_m"] > 0


def test_cut_off_agents_have_outages():
    result = amronet.run(cut_off_scenario(), seed=1)
    s = result.summary
    m = check_mission(s)
    assert m["outages"] > 0 and m["longest_outage_s"] > 0
    assert m["connected_fraction"] < 1.0 and m["time_all_connected_fraction"] < 1.0
    assert any(a["outages"] > 0 for a in m["per_agent"])
    assert s["agents_connected_min"] < 1.0
    files = result.files()
    assert json.loads(files["summary.json"])["mission"] == m


def test_run_books_match_a_step_by_step_check():
    """The run's own books against every step's ``agents_connected`` fed to a plain loop."""
    sim = Simulation(cut_off_scenario(), seed=1)
    seen = []
    for _ in range(300):
        sim.step()
        sw = sim.swarm
        assert np.array_equal(sim.books.relay_mask, sw.role != Role.AGENT)
        seen.append(agents_connected(sim.table, sim.agents, sim.bases, sw.role != Role.AGENT))
    seq = np.array(seen)
    fractions, outages, longest, everyone = reference_outages(seq, sim.dt)
    links = sim.books.agent_links
    assert links is not None and links.steps == 300
    np.testing.assert_allclose(links.connected_fraction, fractions, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(links.outages, outages)
    np.testing.assert_allclose(links.longest_outage_steps * sim.dt, longest, rtol=1e-12)
    assert links.all_connected_fraction == pytest.approx(everyone, abs=1e-15)
    assert links.connected_fraction.mean() == pytest.approx(sim.agents_connected_fraction, abs=1e-12)
    assert outages.sum() > 0


def test_no_mission_without_agents():
    result = amronet.run(amronet.load_scenario("self-spreading-6x6", overrides={"sim.time_limit": 3}), seed=1)
    assert result.summary["mission"] is None
    assert result.run.agent_links is None
    assert json.loads(result.files()["summary.json"])["mission"] is None


def test_mission_fields_are_columns_of_the_stored_runs(tmp_path):
    """The result store keeps ``mission``; its scalars are columns of the runs table, so plots can use them."""
    scenario = cut_off_scenario().to_dict()
    with ResultStore(tmp_path / "r.sqlite") as store:
        for seed in (1, 2):
            store.record("h", seed, scenario, execute_job({"scenario": scenario, "seed": seed}))
        rows = run_rows(store)
    assert [r["status"] for r in rows] == ["done", "done"]
    for name in ("connected_fraction", "longest_outage_s", "outages", "relays_used", "relays_per_100m2_covered",
                 "distance_travelled_m", "time_all_connected_fraction"):
        assert all(isinstance(r[f"mission.{name}"], int | float) for r in rows), name
    groups = plot_groups(rows, "agents.per_base", "mission.longest_outage_s")
    (line,) = groups.values()
    assert line[0]["n"] == 2
    assert line[0]["mean"] == pytest.approx(np.mean([r["mission.longest_outage_s"] for r in rows]))
