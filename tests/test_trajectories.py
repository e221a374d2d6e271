"""Issue #15: agents that follow the paths of a CSV file (``agents.trajectories``): parsing and following."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from amronet.algorithms.agent_assisted.explorers import PathFollower, RandomExplorer
from amronet.cli import main
from amronet.engine.network import agents_connected, connected_to
from amronet.engine.robots import Role
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sweeps import resolve_scenario, scenario_hash
from amronet.world.trajectories import AgentPaths, load_trajectories
from helpers import box_map, open_field_agents

FIELD = "agents.trajectories"


def write(tmp_path, text, name="paths.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def with_paths(tmp_path, csv_text, **over):
    """The open-field agent scenario of the helpers with a trajectory file (one agent per base unless told).

    Agents without a path explore with the paper's ``random`` walk, named here (the default is ``frontier``): the
    tests were written for agents that stay near their base station while the paths are followed.
    """
    path = write(tmp_path, csv_text)
    return open_field_agents(**{"agents.per_base": 1, "agents.trajectories": str(path),
                                "algorithm.params.explorer": "random", **over})


# -- parsing ------------------------------------------------------------------------------------------------------

def test_a_file_is_grouped_by_agent_in_time_order_with_columns_in_any_order(tmp_path):
    path = write(tmp_path, "# a comment\nx, Agent ,y,t\n\n1.0,1,1.0,0\n2.0,0,1.0,0\n3.0,1,1.0,5\n2.0,0,2.0,5.5\n")
    paths = load_trajectories(path, box_map(), n_agents=3)
    assert paths.n_agents == 3 and list(paths.start) == [0, 2, 4, 4]
    assert list(paths.has_path) == [True, True, False]
    assert paths.t.tolist() == [0.0, 5.5, 0.0, 5.0]
    assert paths.xy.tolist() == [[2.0, 1.0], [2.0, 2.0], [1.0, 1.0], [3.0, 1.0]]


@pytest.mark.parametrize(("text", "words"), [
    ("t,agent,x,y\n0,0,1,1\n5,0,2,1\n3,0,3,1\n", "line 4: t = 3 s for agent 0 comes after t = 5 s at line 3; sort"),
    ("t,agent,x,y\n0,0,1,1\n0,1,2.5,2.5\n", "line 3: (2.5, 2.5) is inside a wall"),
    ("t,agent,x,y\n0,0,1,1\n1,7,1,1\n", "line 3: unknown agent 7; the scenario has 2 agents (0..1"),
    ("t,agent,x,y\n0,0,nan,1\n", "line 2: x is nan; give a finite number"),
    ("t,agent,x,y\ninf,0,1,1\n", "line 2: t is inf"),
    ("t,agent,x\n0,0,1\n", "line 1: the header lacks column y"),
    ("t,agent,x,y,heading\n0,0,1,1,0\n", "unknown column 'heading'"),
    ("t,agent,x,x\n0,0,1,1\n", "column 'x' appears twice"),
    ("t,agent,x,y\n0,0,1\n", "line 2: 3 values, but the header has 4 columns"),
    ("t,agent,x,y\n0,0,one,1\n", "line 2: x 'one' is not a number"),
    ("t,agent,x,y\n0,1.5,1,1\n", "line 2: agent 1.5 is not an integer"),
    ("t,agent,x,y\n-2,0,1,1\n", "line 2: t = -2 s is negative"),
    ("t,agent,x,y\n0,0,9,1\n", "line 2: (9, 1) is outside the map [0, 5] x [0, 5]"),
    ("t,agent,x,y\n0,0,1,1\n0,0,4,1\n", "line 3: (4, 1) is free space that cannot be reached from the base stations"),
    ("t,agent,x,y\n0,0,1,1\n2e9,1,1,1\n", "line 3: agent 1's path starts at t = 2e+09 s, after sim.time_limit (300 s)"),
    ("t,agent,x,y\n", "no waypoints after the header"),
    ("# nothing\n\n", "the file is empty"),
])
def test_a_bad_file_is_one_line_naming_the_field_the_file_and_the_line(tmp_path, text, words):
    omap = box_map(walls=[(slice(40, 60), slice(40, 60))])  # 5 m x 5 m, a block over [2, 3] x [2, 3]
    reachable = omap.free.copy()
    reachable[:, 70:] = False  # x > 3.5 m is not reachable
    path = write(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_trajectories(path, omap, n_agents=2, reachable=reachable, time_limit=300.0, shown="paths.csv")
    err = info.value
    assert err.field == FIELD and str(err).startswith(f"{FIELD}: paths.csv")
    assert words in str(err), str(err)
    assert "\n" not in str(err)


def test_the_scenario_checks_the_file_exists_relative_to_its_own_folder(tmp_path):
    folder = tmp_path / "mission"
    folder.mkdir()
    write(folder, "t,agent,x,y\n0,0,3,2\n")
    text = ("map: open-32x32\nalgorithm: {name: agent-assisted}\nradio: {r_c: 4.0}\nbase_stations: [{x: 2, y: 2}]\n"
            "routers: {count: 0}\nagents: {per_base: 1, trajectories: paths.csv}\n")
    (folder / "sc.yaml").write_text(text)
    sc = load_scenario(folder / "sc.yaml")
    assert sc.trajectories_path() == folder / "paths.csv"
    # recorded with its absolute path (summary.json, overrides): the same file wherever it is loaded from
    assert sc.to_dict()["agents"]["trajectories"] == str((folder / "paths.csv").resolve())
    assert load_scenario(sc.to_dict()).trajectories_path() == (folder / "paths.csv").resolve()
    (folder / "other.yaml").write_text(text.replace("paths.csv", "gone.csv"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(folder / "other.yaml")
    assert info.value.field == FIELD and "no file 'gone.csv'" in str(info.value)


@pytest.mark.parametrize(("over", "words"), [
    ({"algorithm.name": "self-spreading", "routers.count": 5}, "self-spreading does not move agents along paths"),
    ({"agents.per_base": 0}, "no agents to follow the paths"),
])
def test_paths_need_agents_that_follow_them(tmp_path, over, words):
    with pytest.raises(ScenarioError) as info:
        with_paths(tmp_path, "t,agent,x,y\n0,0,3,2\n", **over)
    assert info.value.field == FIELD and words in str(info.value)


def test_a_bad_file_on_the_command_line_exits_2_in_one_line_and_writes_nothing(tmp_path, capsys):
    write(tmp_path, "t,agent,x,y\n0,0,3,2\n10,3,8,2\n")
    sc = tmp_path / "sc.yaml"
    sc.write_text("map: open-32x32\nalgorithm: {name: agent-assisted}\nradio: {r_c: 4.0}\n"
                  "base_stations: [{x: 2, y: 2}]\nrouters: {count: 0}\n"
                  "agents: {per_base: 2, trajectories: paths.csv}\n")
    out = tmp_path / "out"
    code = main(["run", str(sc), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"amronet: error: {FIELD}: paths.csv line 3: unknown agent 3")
    assert "Traceback" not in err and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["paths.csv", "sc.yaml"]


def test_the_run_s_identity_holds_the_file_s_absolute_path_and_content(tmp_path):
    sc = with_paths(tmp_path, "t,agent,x,y\n0,0,3,2\n")
    resolved = resolve_scenario(sc)
    assert resolved["agents"]["trajectories"] == str((tmp_path / "paths.csv").resolve())
    before = scenario_hash(resolved)
    write(tmp_path, "t,agent,x,y\n0,0,4,2\n")
    assert scenario_hash(resolved) != before
    assert "trajectories" not in resolve_scenario(open_field_agents())["agents"]  # old runs keep their hashes


# -- following ----------------------------------------------------------------------------------------------------

def follower_on(waypoints, n_agents=1, dt=0.25):
    """A follower of ``waypoints`` ``[(agent, t, x, y), ...]`` (sorted by agent) for Pioneer-sized agents."""
    agent = np.array([w[0] for w in waypoints])
    paths = AgentPaths(t=np.array([w[1] for w in waypoints], dtype=float),
                       xy=np.array([w[2:] for w in waypoints], dtype=float),
                       start=np.concatenate([[0], np.cumsum(np.bincount(agent, minlength=n_agents))]))
    fallback = RandomExplorer(0.5, 0.6, dt, 4.0, (0.0, 10.0, 0.0, 10.0))
    return PathFollower(paths, fallback, dt, np.full(n_agents, 0.5), np.full(n_agents, 0.22))


def steer_blocked(follower, xy, seconds):
    """Steer for ``seconds`` with every move refused: the agents stay where they are."""
    n = len(xy)
    heading = np.zeros(n)
    for _ in range(round(seconds / follower.dt)):
        follower.steer(heading, np.arange(n), np.full((n, 16), 2.0), 2.0, np.ones(n, dtype=bool),
                       np.random.default_rng(0), xy, np.zeros((1, 2)))
    return follower.speed(np.full(n, 0.5))


def test_an_agent_waiting_at_its_waypoint_is_not_taken_for_a_blocked_one():
    follower = follower_on([(0, 0.0, 0.0, 0.0), (0, 20.0, 0.1, 0.0)])
    speed = steer_blocked(follower, np.array([[0.3, 0.0]]), 15.0)
    assert follower.next[0] == 1 and follower.missed[0] == 0 and follower.reached[0] == 1
    assert 0 < speed[0] < 0.1  # it edges onto the exact point at the schedule's pace
    steer_blocked(follower, np.array([[0.3, 0.0]]), 5.5)
    assert follower.reached[0] == 2 and not follower.following[0] and follower.speed(np.full(1, 0.5))[0] == 0.0


def test_a_blocked_agent_skips_its_waypoint_and_the_overdue_ones_behind_it_after_give_up_s():
    follower = follower_on([(0, 0.0, 5.0, 0.0), (0, 0.0, 5.1, 0.0), (0, 30.0, 9.0, 0.0)])
    xy = np.array([[0.0, 0.0]])
    steer_blocked(follower, xy, 4.5)
    assert follower.next[0] == 0 and follower.missed[0] == 0
    speed = steer_blocked(follower, xy, 1.0)
    assert follower.next[0] == 2 and follower.missed[0] == 2  # (9, 0) is not due yet: kept
    assert speed[0] < 0.5 and follower.refused_moves[0] >= 20
    steer_blocked(follower, xy, 5.5)
    assert follower.missed[0] == 3 and not follower.active(1)[0]
    assert follower.report()["path_waypoints_missed"] == 3 and follower.report()["path_finished_agents"] == 1

PATH = [(2.0, 3.5, 2.0), (20.0, 10.0, 2.0), (30.0, 10.0, 2.0), (45.0, 10.0, 8.0), (50.0, 20.0, 8.0)]
"""``(t, x, y)``: out along the field's edge, a 10 s wait, a turn, and a last leg too fast for a Pioneer."""


def test_an_agent_passes_every_waypoint_in_order_on_schedule_then_stops(tmp_path):
    csv_text = "t,agent,x,y\n" + "".join(f"{t},0,{x},{y}\n" for t, x, y in PATH)
    sim = Simulation(with_paths(tmp_path, csv_text), seed=1)
    follower = sim.controller.explorer
    agent = sim.agents[0]
    tol = follower.tolerance[0]
    assert tol == 2 * sim.swarm.radius[agent]  # the agent's diameter
    times, xy, passed = [], [], []
    while sim.t < 120.0 and follower.following.any():
        before = int(follower.next[0])
        sim.step()
        t = sim.t - sim.dt  # the step's decisions were made at its start
        passed += [(t, j) for j in range(before, int(follower.next[0]))]
        times.append(sim.t)
        xy.append(sim.swarm.xy[agent].copy())
    xy, times = np.array(xy), np.array(times)
    assert [j for _, j in passed] == list(range(len(PATH)))
    for (t_pass, _), (t_j, _, _) in zip(passed, PATH, strict=True):
        assert t_pass >= t_j - 1e-9  # never early
    # it comes within tolerance of every waypoint, in order
    first_near = [int(np.argmax(np.hypot(*(xy - (x, y)).T) <= tol)) for _, x, y in PATH]
    assert all(np.hypot(*(xy[k] - (x, y))) <= tol for k, (_, x, y) in zip(first_near, PATH, strict=True))
    assert first_near == sorted(first_near)
    # it waits at (10, 2) from t = 20 to t = 30 and leaves on time
    waiting = (times > 20.0 + 2 * sim.dt) & (times <= 30.0)
    assert np.hypot(*(xy[waiting] - (10.0, 2.0)).T).max() <= 1e-6
    # on time until the last leg (10 m in 5 s at 0.5 m/s: 15 s late), then it stops at the last waypoint
    report = sim.controller.mission_report()
    assert report["path_waypoints_reached"] == 5 and report["path_waypoints_missed"] == 0
    assert report["path_finished_agents"] == 1 and 14.0 <= report["path_late_max_s"] <= 16.0
    assert np.hypot(*(xy[-1] - PATH[-1][1:])) <= tol
    stopped = sim.swarm.xy[agent].copy()
    for _ in range(5):
        sim.step()
    assert np.array_equal(sim.swarm.xy[agent], stopped)


def test_a_replayed_mission_runs_to_the_end_of_its_paths(tmp_path):
    csv_text = "t,agent,x,y\n" + "".join(f"{t},0,{x},{y}\n" for t, x, y in PATH)
    result = Simulation(with_paths(tmp_path, csv_text), seed=2).run()
    s = result.summary
    assert s["stop_reason"] == "settled" and 64.0 <= s["sim_time_s"] <= 70.0
    assert s["mission"]["relays_used"] >= 3 and s["mission"]["path_waypoints_reached"] == 5
    assert s["agents_connected_fraction"] == 1.0


def test_agents_are_numbered_base_by_base_and_those_without_a_path_explore(tmp_path):
    bases = [{"x": 2.0, "y": 2.0, "region": [1.6, 1.6]}, {"x": 30.0, "y": 2.0, "region": [1.6, 1.6]}]
    sc = with_paths(tmp_path, "t,agent,x,y\n0,2,30,4\n10,2,30,9\n", **{"agents.per_base": 2,
                                                                      "base_stations": bases})
    sim = Simulation(sc, seed=3)
    for _ in range(80):
        sim.step()
    moved = sim.swarm.distance[sim.agents]
    assert sim.swarm.status[sim.agents[2]] == 1  # agent 2: the first of base station 1
    assert np.hypot(*(sim.swarm.xy[sim.agents[2]] - (30.0, 9.0))) <= sim.controller.explorer.tolerance[2]
    assert (moved[[0, 1, 3]] > 5.0).all()  # the others explore (20 s at 0.5 m/s)
    assert not sim.controller.unsettled()[sim.agents].any()  # but the mission is the one path, and it has ended


def test_a_path_through_a_wall_is_refused_and_skipped_without_getting_stuck(tmp_path):
    # office-32x32: from the bottom corridor straight into the room behind its wall, then back along the corridor
    sc = with_paths(tmp_path, "t,agent,x,y\n0,0,4,1.2\n5,0,4,5\n20,0,10,1.2\n",
                    **{"map": "office-32x32", "base_stations": [{"x": 1.0, "y": 1.0, "region": [1.6, 1.6]}],
                       "sim.dt": 0.1})
    result = Simulation(sc, seed=1).run()
    mission = result.summary["mission"]
    assert result.summary["stop_reason"] == "settled" and result.summary["sim_time_s"] < 60.0
    assert mission["path_waypoints_missed"] == 1 and mission["path_waypoints_reached"] == 2


def test_routers_released_along_a_path_in_the_office_stay_linked_to_the_base_station(tmp_path):
    """Along the bottom corridor, up the middle one, across and up the right-hand one; the second agent explores."""
    waypoints = [(0, 2.0, 1.2), (30, 16.0, 1.2), (60, 16.0, 16.0), (90, 30.6, 16.0), (120, 30.6, 30.6)]
    csv_text = "t,agent,x,y\n" + "".join(f"{t},0,{x},{y}\n" for t, x, y in waypoints)
    sc = with_paths(tmp_path, csv_text, **{"map": "office-32x32", "agents.per_base": 2, "sim.dt": 0.1,
                                           "base_stations": [{"x": 1.0, "y": 1.0, "region": [1.6, 1.6]}]})
    sim = Simulation(sc, seed=4)
    follower = sim.controller.explorer
    while follower.following.any():
        sim.step()
        sw = sim.swarm
        assert agents_connected(sim.table, sim.agents, sim.bases, sw.role != Role.AGENT).all()
        deployed = sw.deployed
        assert connected_to(sim.table, sim.bases, deployed)[deployed].all(), "a deployed router is cut off"
        assert sim.t < 200.0
    assert sim.controller.released_by[0] >= 4
    assert follower.missed.sum() == 0
    assert np.hypot(*(sim.swarm.xy[sim.agents[0]] - waypoints[-1][1:])) <= follower.tolerance[0]
    json.dumps(sim.controller.mission_report())  # plain data for summary.json


def test_a_replayed_mission_is_the_same_with_the_compiled_step_and_the_reference(tmp_path):
    """Agents on paths (and one exploring at random) step the same through the compiled agent step and the phases."""
    csv_text = "t,agent,x,y\n0,1,2,2\n60,1,20,2\n120,1,20,20\n180,1,5,25\n"
    sc = with_paths(tmp_path, csv_text, **{"agents.per_base": 2, "sim.time_limit": 220.0})
    compiled, reference = Simulation(sc, 4), Simulation(sc, 4, step="reference")
    assert compiled.compiled is not None and reference.compiled is None
    a, b = compiled.run(), reference.run()
    np.testing.assert_array_equal(compiled.swarm.xy, reference.swarm.xy)
    np.testing.assert_array_equal(compiled.swarm.state, reference.swarm.state)
    assert a.network == b.network and compiled.rows == reference.rows


@pytest.mark.parametrize("x", ["1e300", "-1e300", "1e19", "1.7976931348623157e308"])
def test_a_waypoint_far_off_the_map_is_one_error_and_no_warning(tmp_path, x, recwarn):
    """Issue #45 (5g): checked against the map's extent before any cell arithmetic (which overflowed, warning)."""
    path = write(tmp_path, f"t,agent,x,y\n0,0,1,1\n10,0,{x},1\n")
    with pytest.raises(ScenarioError) as info:
        load_trajectories(path, box_map(), n_agents=1, shown="paths.csv")
    where = f"{FIELD}: paths.csv line 3: ({float(x):g}, 1) is outside the map [0, 5] x [0, 5]"
    assert str(info.value).startswith(where)
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_a_waypoint_far_off_the_map_on_the_command_line_is_exactly_one_line(tmp_path):
    """Issue #45 (5g): stderr is the one error line, no numpy RuntimeWarning before it (a real process: pytest would
    capture the warnings in its own)."""
    write(tmp_path, "t,agent,x,y\n0,0,3,2\n10,0,1e300,2\n")
    sc = tmp_path / "sc.yaml"
    sc.write_text("map: open-32x32\nalgorithm: {name: agent-assisted}\nradio: {r_c: 4.0}\n"
                  "base_stations: [{x: 2, y: 2}]\nrouters: {count: 0}\n"
                  "agents: {per_base: 1, trajectories: paths.csv}\n")
    exe = Path(sys.executable).with_name("amronet")
    proc = subprocess.run([str(exe), "run", str(sc), "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith(f"amronet: error: {FIELD}: paths.csv line 3: (1e+300, 2) is outside the map")
    assert not (tmp_path / "out").exists()
