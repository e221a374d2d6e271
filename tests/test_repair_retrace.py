"""``repair: retrace``: a cut-off router backs up the way it was carried in; the straight move of ``relocate`` cannot.

The hand-built case: two rooms side by side, a wall between them with a door at the top; the multi-wall radio
(r_c 4 m: through one wall a link reaches about 1.8 m). One agent walks from the base station in the left room
past P to F by the wall, up through the door and down the right room to C, right across the wall from F, and home
again. P, F and C are put down there by hand (the agent's drop rule never fires: ``radius`` at twice ``r_c``), so
that C's only link is F's, through the wall. F fails. ``relocate`` drives C straight toward F, into the wall, where
it still hears nobody; ``retrace`` backs C up the agent's way, through the door, until it hears P.
"""

from __future__ import annotations

import numpy as np
import pytest

import amronet
from amronet.engine.network import connected_to
from amronet.engine.robots import State
from amronet.errors import ScenarioError
from amronet.sim import Simulation
from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap

RES = 0.05
P, F, C = (3.0, 3.0), (5.4, 3.0), (6.6, 3.0)
"""Where the agent stands when it puts P, F and C down."""
PATH = [(0, 1.0, 1.0), (10, 3.0, 3.0), (20, 3.0, 3.0), (30, 5.4, 3.0), (40, 5.4, 3.0), (52, 5.4, 7.2),
        (58, 6.6, 7.2), (70, 6.6, 3.0), (80, 6.6, 3.0), (92, 6.6, 7.2), (98, 5.4, 7.2), (115, 1.2, 1.6)]
"""The agent's timed way: (t, x, y); it waits at P's, F's and C's places."""
DROPS = {15.0: P, 35.0: F, 75.0: C}
FAULT_AT = 130.0
END = 260.0


def two_rooms() -> OccupancyMap:
    """12 m x 8 m, outer walls, a 10 cm wall at x = 6 m from the floor up to y = 6.5 m (the door above it)."""
    cells = np.full((160, 240), FREE, dtype=np.int8)
    cells[:2, :] = cells[-2:, :] = cells[:, :2] = cells[:, -2:] = OCCUPIED
    cells[:130, 119:121] = OCCUPIED  # rows are y from the origin (row 0 at y = 0)
    return OccupancyMap(name="two-rooms", resolution=RES, origin=(0.0, 0.0), cells=cells)


def scenario(tmp_path, repair: str, **params):
    path = tmp_path / "way.csv"
    path.write_text("t,agent,x,y\n" + "".join(f"{t},0,{x},{y}\n" for t, x, y in PATH))
    return amronet.load_scenario({
        "map": "open-32x32", "radio": {"model": "multi-wall", "r_c": 4.0},
        "algorithm": {"name": "agent-assisted", "params": {"repair": repair, "drop_rule": "radius",
                                                           "drop": {"radius": 2.0}, **params}},
        "base_stations": [{"x": 1.0, "y": 1.0, "region": [1.0, 1.0]}], "routers": {"count": 0},
        "agents": {"per_base": 1, "trajectories": str(path)},
        "sim": {"dt": 0.25, "time_limit": 260.0, "coverage_target": "off"},
        "faults": [{"at": FAULT_AT, "ids": [3]}]})


def run_two_rooms(tmp_path, repair: str, seed: int = 1):
    """The case above, run to its end: the simulation, and the ids of P, F, C (F is node 3, the fault's)."""
    sim = Simulation(scenario(tmp_path, repair), seed=seed, omap=two_rooms())
    ctrl, agent = sim.controller, int(sim.agents[0])
    placed = []
    while sim.t < END - 1e-9:
        for t, where in DROPS.items():
            if abs(sim.t - t) < 1e-9:
                assert np.hypot(*(sim.swarm.xy[agent] - where)) < 0.05, "the agent is not where the drop is due"
                toward = placed[-1] if placed else int(sim.bases[0])
                placed.append(ctrl._release_reference(agent, toward, sim.t))
        sim.step()
    return sim, placed


def restored_after(sim):
    """The fault's ``restored_after_s`` in the run's books."""
    return sim.books.fault_book.summary(sim.books, None)["events"][0]["restored_after_s"]


@pytest.fixture(scope="module")
def two_room_runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rooms")
    return {repair: run_two_rooms(tmp, repair) for repair in ("none", "relocate", "retrace")}


def test_the_case_is_what_it_says(two_room_runs):
    sim, (p, f, c) = two_room_runs["none"]
    assert f == 3 and sim.swarm.state[f] == State.FAILED
    xy = sim.swarm.xy
    assert xy[f][0] < 6.0 < xy[c][0] and abs(xy[f][1] - xy[c][1]) < 0.5  # across the wall from each other
    linked = connected_to(sim.table, sim.books.live_bases, sim.swarm.relaying)
    assert linked[p] and not linked[c]  # without repair C stays cut off
    assert restored_after(sim) is None


def test_a_straight_move_toward_the_failed_router_does_not_reconnect(two_room_runs):
    sim, (_, _, c) = two_room_runs["relocate"]
    xy = sim.swarm.xy
    assert sim.swarm.state[c] == State.REFERENCE and xy[c][0] > 6.0  # it drove into the wall and gave up there
    assert np.hypot(*(xy[c] - np.array(C))) > 0.2  # it did move
    assert not connected_to(sim.table, sim.books.live_bases, sim.swarm.relaying)[c]
    assert restored_after(sim) is None


def test_retracing_the_way_in_reconnects(two_room_runs):
    sim, (_, _, c) = two_room_runs["retrace"]
    sw = sim.swarm
    assert connected_to(sim.table, sim.books.live_bases, sw.relaying)[c]
    assert sw.xy[c][0] < 6.0 and sw.state[c] == State.REFERENCE  # back through the door, in P's room
    assert sim.controller.mission_report()["relocations"] == 1
    assert 0 < restored_after(sim) <= 120.0


def test_retrace_is_deterministic(tmp_path):
    a = Simulation(scenario(tmp_path, "retrace"), seed=4, omap=two_rooms())
    b = Simulation(scenario(tmp_path, "retrace"), seed=4, omap=two_rooms())
    for sim in (a, b):
        ctrl, agent, placed = sim.controller, int(sim.agents[0]), []
        while sim.t < END - 1e-9:
            if any(abs(sim.t - t) < 1e-9 for t in DROPS):
                placed.append(ctrl._release_reference(agent, placed[-1] if placed else int(sim.bases[0]), sim.t))
            sim.step()
    assert np.array_equal(a.swarm.xy, b.swarm.xy) and np.array_equal(a.swarm.state, b.swarm.state)
    assert np.array_equal(a.swarm.distance, b.swarm.distance)


@pytest.mark.parametrize(("params", "field"), [
    ({"repair": "retrace-all"}, "algorithm.params.repair"),
    ({"repair": "retrace", "repair_confirm_s": -1.0}, "algorithm.params.repair_confirm_s"),
])
def test_bad_repair_parameters_are_one_line_errors(params, field):
    with pytest.raises(ScenarioError) as err:
        amronet.load_scenario("agent-assisted-office",
                              overrides={f"algorithm.params.{k}": v for k, v in params.items()})
    assert err.value.field == field and "\n" not in str(err.value)


def test_retrace_with_routers_larger_than_the_agents_is_refused_in_one_line():
    sc = amronet.load_scenario("agent-assisted-office", overrides={
        "algorithm.params.repair": "retrace", "routers.robot": "pioneer", "agents.robot": "amigobot"})
    with pytest.raises(ScenarioError) as err:
        Simulation(sc, seed=1)
    assert err.value.field == "algorithm.params.repair" and "\n" not in str(err.value)


def test_bad_repair_on_the_command_line_exits_2_and_writes_nothing(tmp_path, capsys):
    from amronet.cli.main import main

    out = tmp_path / "r"
    code = main(["run", "--preset", "agent-assisted-office", "--out", str(out),
                 "--set", "algorithm.params.repair=retrace", "--set", "routers.robot=pioneer",
                 "--set", "agents.robot=amigobot"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("amronet: error: algorithm.params.repair")
    assert not out.exists()
    assert main(["run", "--preset", "agent-assisted-office", "--out", str(out),
                 "--set", "algorithm.params.repair=backtrack"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "algorithm.params.repair" in err and "retrace" in err
    assert not out.exists()


PAIR_WAY = [(0, 1.0, 1.0), (10, 4.0, 1.0), (20, 4.0, 1.0), (30, 7.0, 1.0), (40, 7.0, 1.0), (50, 10.0, 1.0),
            (60, 10.0, 1.0), (68, 10.0, 3.0), (78, 10.0, 3.0), (110, 1.2, 2.0)]
"""One agent, on the unit disk (r_c 4 m): P at 3 m from the base, F 3 m on, C1 3 m past F, C2 2 m beside C1."""
PAIR_DROPS = {15.0: (4.0, 1.0), 35.0: (7.0, 1.0), 55.0: (10.0, 1.0), 73.0: (10.0, 3.0)}


def run_pair(tmp_path, repair: str = "retrace"):
    """F (node 3) fails at 130 s and cuts off C1 and C2, which hear each other and both lost F; run to 200 s."""
    path = tmp_path / "pair.csv"
    path.write_text("t,agent,x,y\n" + "".join(f"{t},0,{x},{y}\n" for t, x, y in PAIR_WAY))
    sc = amronet.load_scenario({
        "map": "open-32x32", "radio": {"r_c": 4.0},
        "algorithm": {"name": "agent-assisted", "params": {"repair": repair, "drop_rule": "radius",
                                                           "drop": {"radius": 2.0}}},
        "base_stations": [{"x": 1.0, "y": 1.0, "region": [1.0, 1.0]}], "routers": {"count": 0},
        "agents": {"per_base": 1, "trajectories": str(path)},
        "sim": {"dt": 0.25, "time_limit": 200.0, "coverage_target": "off"},
        "faults": [{"at": FAULT_AT, "ids": [3]}]})
    sim = Simulation(sc, seed=1)
    ctrl, agent, placed = sim.controller, int(sim.agents[0]), []
    while sim.t < 200.0 - 1e-9:
        for t, where in PAIR_DROPS.items():
            if abs(sim.t - t) < 1e-9:
                assert np.hypot(*(sim.swarm.xy[agent] - where)) < 0.05, "the agent is not where the drop is due"
                placed.append(ctrl._release_reference(agent, placed[-1] if placed else int(sim.bases[0]), sim.t))
        sim.step()
    return sim, placed


def test_of_two_cut_off_routers_that_hear_each_other_one_backs_up_and_the_other_waits(tmp_path):
    sim, (p, f, c1, c2) = run_pair(tmp_path)
    assert f == 3 and sim.swarm.state[f] == State.FAILED
    summary = sim.books.fault_book.summary(sim.books, None)
    assert summary["events"][0]["restored_after_s"] is not None
    assert connected_to(sim.table, sim.books.live_bases, sim.swarm.relaying)[[p, c1, c2]].all()
    moved = sim.swarm.distance
    assert moved[c1] > 0.5 and moved[c2] == 0.0  # C2 waited, and C1 took it along when it reconnected
    assert summary["routers_moved"] == 1 and sim.controller.mission_report()["relocations"] == 1
