"""Node failures (issue #16): parsing, scheduling, what a failed node is, and the books of the damage."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import amronet
from amronet.engine.network import connected_to
from amronet.engine.robots import Role, State
from amronet.errors import ScenarioError
from amronet.sim import Simulation
from amronet.sim.batch import batchable


def spreading(faults, **over):
    base = {"faults": faults, "sim.time_limit": 120.0, "sim.stop_when_settled": False}
    return amronet.load_scenario("self-spreading-6x6", overrides={**base, **over})


@pytest.mark.parametrize(("faults", "field"), [
    ([{"at": 10}], "faults[0]"),
    ([{"at": 10, "routers": 0.2, "ids": [1]}], "faults[0]"),
    ([{"routers": 0.2}], "faults[0].at"),
    ([{"at": 10, "routers": 1.5}], "faults[0].routers"),
    ([{"at": -1, "ids": [2]}], "faults[0].at"),
    ([{"at": 1, "ids": [2]}, {"at": 5, "base_station": 2}], "faults[1].base_station"),
    ([{"rate_per_hour": 0}], "faults[0].rate_per_hour"),
    ([{"at": 1, "nodes": [2]}], "faults[0].nodes"),
])
def test_bad_fault_entries_are_one_line_errors(faults, field):
    with pytest.raises(ScenarioError) as err:
        spreading(faults)
    assert err.value.field == field and "\n" not in str(err.value)


def test_bad_faults_on_the_command_line_exit_2_and_write_nothing(tmp_path, capsys):
    from amronet.cli.main import main

    code = main(["run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "r"), "--set", "faults=[{at: 5}]"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "faults[0]" in err
    assert not (tmp_path / "r").exists()


def test_a_fraction_of_the_deployed_routers_fails_when_due_and_is_silent_from_then_on():
    sim = Simulation(spreading([{"at": 60.0, "routers": 0.5}]), seed=3)
    while sim.t < 60.0:
        sim.step()
        assert not (sim.swarm.state == State.FAILED).any()
    deployed = np.flatnonzero(sim.swarm.deployed & (sim.swarm.role == Role.ROUTER))
    sim.step()
    failed = np.flatnonzero(sim.swarm.state == State.FAILED)
    assert len(failed) == round(0.5 * len(deployed)) and set(failed) <= set(deployed)
    positions = sim.swarm.xy[failed].copy()
    for _ in range(50):
        sim.step()
    table = sim.table
    assert all(table.indptr[i] == table.indptr[i + 1] for i in failed)  # no links: they send nothing
    geometric = table.geometric
    assert any(geometric.indptr[i + 1] > geometric.indptr[i] for i in failed)  # still bodies the others sense
    assert np.array_equal(sim.swarm.xy[failed], positions)  # and they stay where they are
    linked = connected_to(table, sim.books.live_bases, sim.swarm.relaying)
    assert not linked[failed].any()


def test_faults_are_deterministic_and_leave_the_run_before_them_unchanged():
    plain = amronet.run(spreading([]), seed=5)
    a = amronet.run(spreading([{"at": 80.0, "routers": 0.3}, {"rate_per_hour": 200.0, "at": 90.0}]), seed=5)
    b = amronet.run(spreading([{"at": 80.0, "routers": 0.3}, {"rate_per_hour": 200.0, "at": 90.0}]), seed=5)
    assert a.network == b.network and a.summary["faults"] == b.summary["faults"]
    rows_before = [r for r in plain.timeseries["t"] if r < 80.0]
    k = len(rows_before)
    for name in ("coverage", "connected_coverage", "routers_deployed"):
        assert np.array_equal(plain.timeseries[name][:k], a.timeseries[name][:k])
    kinds = [e["kind"] for e in a.summary["faults"]["events"]]
    assert kinds[0] == "routers" and "rate_per_hour" in kinds
    assert a.summary["faults"]["nodes_failed"] == sum(len(e["nodes"]) for e in a.summary["faults"]["events"])
    assert "faults" not in plain.summary


def test_a_base_station_that_fails_takes_its_network_down():
    result = amronet.run(spreading([{"at": 60.0, "base_station": 0}]), seed=2)
    event = result.summary["faults"]["events"][0]
    assert event["nodes"] == [0] and event["connected_coverage_after"] == 0.0
    assert event["coverage_before"] > 0.0 and event["restored_after_s"] is None
    assert result.summary["connected_coverage"] == 0.0 and result.summary["routers_connected_fraction"] == 0.0


def test_unknown_ids_are_skipped_and_said():
    result = amronet.run(spreading([{"at": 30.0, "ids": [2, 999]}]), seed=1)
    faults = result.summary["faults"]
    assert faults["events"][0]["nodes"] == [2]
    assert "999" in faults["skipped"][0]


def test_a_cut_in_the_agents_chain_is_counted_until_repaired():
    """Agents in an open field: a router of the chain fails; the agents' outages and the restore time say so."""
    sc = amronet.load_scenario("agent-assisted-office", overrides={
        "map": "open-32x32", "radio.r_c": 4.0, "agents.per_base": 1, "algorithm.params.explorer": "frontier",
        "sim.time_limit": 160.0, "sim.coverage_target": 1.0, "faults": [{"at": 100.0, "routers": 1.0}]})
    result = amronet.run(sc, seed=1)
    faults = result.summary["faults"]
    event = faults["events"][0]
    assert len(event["nodes"]) >= 2 and event["connected_coverage_after"] < event["connected_coverage_before"]
    mission = result.summary["mission"]
    assert mission["outages"] >= 1  # the agent was cut off: its whole chain failed
    restored = event["restored_after_s"]
    assert restored is None or restored > 0
    assert faults["extra_routers"] >= 0


def test_runs_with_faults_are_not_batched():
    assert batchable(spreading([]))
    assert not batchable(spreading([{"at": 5.0, "routers": 0.1}]))


def test_the_failures_experiment_writes_its_table_and_figure(tmp_path):
    from amronet.experiments.failures import run_failures
    from amronet.experiments.options import RunOptions

    out = tmp_path / "failures"
    report = run_failures(out, maps=("autolab",), fractions=(0.3,), runs=2, fault_at=40.0, after=20.0,
                          options=RunOptions(workers=1, show_progress=False), radios=("unit-disk", "multi-wall"))
    assert len(report["rows"]) == 12
    cells = {(r["radio"], r["algorithm"]) for r in report["rows"]}
    assert cells == {("unit-disk", a) for a in ("self-spreading", "agent-assisted", "agent-assisted-relocate",
                                                "agent-assisted-retrace")} | {
        ("multi-wall", "agent-assisted-relocate"), ("multi-wall", "agent-assisted-retrace")}
    for r in report["rows"]:
        assert r["failed"] >= 1 and r["connected_after"] <= r["connected_before"] + 1e-12
    for name in ("failures.png", "failures-multi-wall.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG"
    text = (out / "failures.md").read_text()
    assert "## unit-disk" in text and "## multi-wall" in text and "| autolab | agent-assisted | 30 % |" in text
    assert "| autolab | agent-assisted-retrace | 30 % |" in text.split("## multi-wall")[1]


def test_the_failures_experiment_keeps_the_seeds_of_its_first_cells_and_refuses_unknown_names(tmp_path):
    from amronet.errors import AmronetError
    from amronet.experiments.failures import _cell_index, _scenario, run_failures
    from amronet.experiments.options import RunOptions

    # the first version's cells, in its order (map, algorithm, fraction; 20 runs each): the same seeds as then
    assert _cell_index("office-32x32", "unit-disk", "self-spreading", 0.1) == 0
    assert _cell_index("autolab", "unit-disk", "agent-assisted-relocate", 0.3) == 17
    later = {_cell_index(m, r, "agent-assisted-retrace", f) for m in ("autolab", "hospital_section")
             for r in ("unit-disk", "multi-wall") for f in (0.1, 0.2, 0.3)}
    assert len(later) == 12 and min(later) >= 18
    walls = _scenario("agent-assisted-retrace", "autolab", 0.2, 60.0, 60.0, "frontier", "multi-wall")
    assert walls["radio"]["model"] == "multi-wall" and walls["algorithm"]["params"]["drop_rule"] == "link-quality"
    assert walls["algorithm"]["params"]["repair"] == "retrace"
    plain = _scenario("agent-assisted-relocate", "autolab", 0.2, 60.0, 60.0, "frontier")
    assert plain["radio"] == {"model": "unit-disk", "r_c": 4.0} and "drop_rule" not in plain["algorithm"]["params"]
    with pytest.raises(AmronetError, match="unknown radio 'walls'"):
        run_failures(tmp_path / "x", radios=("walls",), options=RunOptions(workers=1, show_progress=False))
    assert not (tmp_path / "x").exists()


def test_coverage_target_off_lets_agents_go_on_after_full_coverage():
    sc = amronet.load_scenario("agent-assisted-office", overrides={
        "map": "open-32x32", "radio.r_c": 10.0, "algorithm.params.explorer": "frontier", "sim.time_limit": 120.0,
        "sim.coverage_target": "off"})
    result = amronet.run(sc, seed=1)
    assert result.summary["stop_reason"] == "time_limit" and result.summary["coverage_target"] is None
    with pytest.raises(ScenarioError, match=r"sim\.coverage_target"):
        amronet.load_scenario("agent-assisted-office", overrides={"sim.coverage_target": "never"})


def corridor_run(repair: str, seed: int = 1):
    """One agent lays a chain along a 30 m corridor; at t = 100 s the second router of the chain fails."""
    from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap

    cells = np.full((30, 600), FREE, dtype=np.int8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    omap = OccupancyMap(name="corridor", resolution=0.05, origin=(0.0, 0.0), cells=cells)
    sc = amronet.load_scenario({
        "map": "open-32x32", "radio": {"r_c": 4.0},
        "algorithm": {"name": "agent-assisted", "params": {"explorer": "frontier", "repair": repair}},
        "base_stations": [{"x": 0.75, "y": 0.75, "region": [1.0, 1.0]}], "routers": {"count": 0},
        "agents": {"per_base": 1}, "sim": {"dt": 0.25, "time_limit": 200.0, "coverage_target": "off"},
        "faults": [{"at": 100.0, "ids": [3]}]})
    sim = Simulation(sc, seed=seed, omap=omap)
    return sim, sim.run()


def test_relocation_bridges_a_cut_in_a_corridor_and_the_chain_stays_without_it():
    _, plain = corridor_run("none")
    event = plain.summary["faults"]["events"][0]
    assert event["nodes"] == [3] and event["connected_coverage_after"] < 0.5
    assert event["restored_after_s"] is None and plain.summary["routers_connected_fraction"] < 0.5
    sim, fixed = corridor_run("relocate")
    faults = fixed.summary["faults"]
    assert faults["events"][0]["restored_after_s"] is not None  # every survivor has a path again
    assert faults["routers_moved"] >= 1 and faults["repair_distance_m"] > 0
    assert fixed.summary["mission"]["relocations"] >= 1
    assert fixed.summary["routers_connected_fraction"] == 1.0 and fixed.summary["connected_coverage"] > 0.95
    sw = sim.swarm
    assert sw.state[3] == State.FAILED and not connected_to(sim.table, sim.books.live_bases, sw.relaying)[3]
    assert not (sw.state == State.RELOCATING).any()  # every relocation ended


def test_relocation_is_deterministic():
    _, a = corridor_run("relocate", seed=2)
    _, b = corridor_run("relocate", seed=2)
    assert a.network == b.network and a.summary["faults"] == b.summary["faults"]


@settings(max_examples=150, deadline=None)
@given(at=st.floats(0.0, 50.0), dt=st.sampled_from([0.1, 0.05, 0.2, 0.3, 1.0 / 3.0]), step=st.integers(0, 600),
       limit=st.integers(1, 40), poisson=st.booleans())
def test_quiet_steps_are_the_steps_in_which_due_finds_and_draws_nothing(at, dt, step, limit, poisson):
    """What a stretch may take in a run with faults (amronet.sim.loop.Loop._stretch), against due() step by step."""
    from amronet.scenario.schema import FaultSpec
    from amronet.sim.faults import FaultSchedule

    # a Poisson rate so high that every step it is on fails a router: a step that draws has an event
    spec = FaultSpec(rate_per_hour=1e12, at=at) if poisson else FaultSpec(at=at, ids=[1])
    schedule = FaultSchedule([spec], np.array([0]), dt, np.random.default_rng(0))
    quiet = schedule.quiet_steps(step, limit)
    role, deployed = np.array([Role.BASE, Role.ROUTER]), np.array([True, True])
    expected = 0
    while expected < limit:
        state = np.full(2, State.REFERENCE)
        if schedule.due((step + expected) * dt, role, state, deployed):
            break
        expected += 1
    assert quiet == expected


@settings(max_examples=100, deadline=None)
@given(at=st.floats(0.0, 20.0), dt=st.sampled_from([0.1, 0.05, 0.2, 1.0 / 3.0]), poisson=st.booleans())
def test_pending_is_false_exactly_in_the_steps_in_which_due_finds_and_draws_nothing(at, dt, poisson):
    """The loop's faults phase asks pending() before due() (amronet.sim.loop.Loop._fail_nodes)."""
    from amronet.scenario.schema import FaultSpec
    from amronet.sim.faults import FaultSchedule

    spec = FaultSpec(rate_per_hour=1e12, at=at) if poisson else FaultSpec(at=at, ids=[1])
    schedule = FaultSchedule([spec], np.array([0]), dt, np.random.default_rng(0))
    role, deployed = np.array([Role.BASE, Role.ROUTER]), np.array([True, True])
    for step in range(round(at / dt) + 3):
        drawn = schedule.rng.bit_generator.state
        pending = schedule.pending(step * dt)
        events = schedule.due(step * dt, role, np.full(2, State.REFERENCE), deployed)
        assert pending == bool(events)
        if not pending:
            assert schedule.rng.bit_generator.state == drawn
