"""The ``strip-goals`` drop rule: the r-strip lattice's goal points, the choice of a goal, and runs that use it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import amronet
from amronet.algorithms.agent_assisted.drops import DROP_RULES, DropContext, validate_drop_params
from amronet.algorithms.agent_assisted.drops.strip_goals import ROW_GAP, strip_goal_points
from amronet.algorithms.agent_assisted.stretch import QuietStretch
from amronet.engine.network import connected_to
from amronet.engine.robots import State
from amronet.errors import ScenarioError
from amronet.experiments.buildings import BUILDINGS, RADIOS
from amronet.experiments.common import agent_scenario
from amronet.sim import Simulation

R_C = 4.0
CONTEXT = DropContext(r_c=R_C, r_eff=0.95 * R_C, dt=0.1, n_agents=1, sensor_range=3.0)


def rule(**params):
    cls = DROP_RULES["strip-goals"]
    return cls(validate_drop_params(cls, params, "algorithm.params.drop"), CONTEXT)


@settings(max_examples=40, deadline=None)
@given(ox=st.floats(-20, 20), oy=st.floats(-20, 20), cx=st.floats(-20, 20), cy=st.floats(-20, 20),
       s=st.floats(0.5, 5))
def test_lattice_points_are_the_r_strip_and_every_connector_joins_two_rows(ox, oy, cx, cy, s):
    origin, centre = np.array([ox, oy]), np.array([cx, cy])
    rows, connectors = strip_goal_points(origin, s, centre, 2.5 * s)
    assert len(rows) and len(connectors)
    assert (np.hypot(*(rows - centre).T) <= 2.5 * s + 1e-9).all()
    rel = rows - origin
    j = np.round(rel[:, 1] / (ROW_GAP * s))
    assert np.allclose(rel[:, 1], j * ROW_GAP * s, atol=1e-9)  # on a row
    i = (rel[:, 0] - (j % 2) * s / 2) / s
    assert np.allclose(i, np.round(i), atol=1e-9)  # s apart, odd rows shifted by s/2
    # each connector is 0.966 s from a point of its row and from one of the next row, and from no point nearer
    all_rows, _ = strip_goal_points(origin, s, centre, 6 * s)
    for c in connectors:
        d = np.sort(np.hypot(*(all_rows - c).T))
        assert d[0] == pytest.approx(math.hypot(0.25, ROW_GAP / 2) * s) == pytest.approx(d[1])
        assert d[0] < s


def test_the_origin_is_a_row_point():
    rows, _ = strip_goal_points(np.array([1.0, 1.0]), 2.0, np.array([1.0, 1.0]), 0.1)
    assert np.allclose(rows, [[1.0, 1.0]])


def test_goal_is_the_nearest_free_row_point_linked_to_the_reference():
    r = rule()
    s = r.params.spacing * R_C
    origin = np.array([0.0, 0.0])
    # reference at the origin; put down east of it: the row point s east is nearest
    goal = r.goal(np.array([3.6, 0.3]), origin, origin, taken_xy=origin[None])
    assert np.allclose(goal, [s, 0.0])
    assert np.hypot(*goal) <= r.keep_radius()
    # that one taken (another router's goal within s / 2): the next nearest row point, west
    goal2 = r.goal(np.array([3.6, 0.3]), origin, origin, taken_xy=np.array([[0.0, 0.0], [s + 0.3, 0.1]]))
    assert np.allclose(goal2, [-s, 0.0])


def test_a_connector_only_when_no_row_point_is_free_and_none_when_all_are_taken():
    r = rule()
    s = r.params.spacing * R_C
    origin = np.array([0.0, 0.0])
    rows, connectors = strip_goal_points(origin, s, origin, r.keep_radius())
    goal = r.goal(np.array([0.5, 3.0]), origin, origin, taken_xy=rows)
    assert any(np.allclose(goal, c) for c in connectors)
    assert r.goal(np.array([0.5, 3.0]), origin, origin, taken_xy=np.concatenate([rows, connectors])) is None


def test_a_lattice_anchored_elsewhere_gives_other_goals():
    r = rule()
    a = r.goal(np.array([3.0, 0.0]), np.zeros(2), np.zeros(2), taken_xy=np.zeros((1, 2)))
    b = r.goal(np.array([3.0, 0.0]), np.zeros(2), np.array([1.3, 0.7]), taken_xy=np.zeros((1, 2)))
    assert not np.allclose(a, b)


# -- runs -----------------------------------------------------------------------------------------------------------
def office(**overrides):
    base = {"sim.time_limit": 90.0, "algorithm.params.explorer": "frontier",
            "algorithm.params.drop_rule": "strip-goals"}
    return amronet.load_scenario("agent-assisted-office", overrides={**base, **overrides})


def test_routers_drive_to_lattice_goals_and_the_network_stays_connected():
    sim = Simulation(office(), seed=3)
    saw_strip = False
    for k in range(900):
        sim.step()
        if sim.terminated:
            break
        driving = sim.swarm.state == State.STRIP
        saw_strip |= bool(driving.any())
        if k % 10 == 0:  # every deployed or driving router has a path to a base station
            nodes = sim.swarm.deployed | driving
            nodes[len(sim.table.indptr) - 1:] = False
            n = len(sim.table.indptr) - 1
            assert connected_to(sim.table, sim.bases, nodes[:n])[nodes[:n]].all(), "a router is cut off"
    assert saw_strip
    c = sim.controller
    report = c.mission_report()["strip_goals"]
    assert report["reached"] >= 1
    sw = sim.swarm
    base = sw.xy[c.bases[0]]
    s = c.drop_rule.params.spacing * sim.scenario.radio.r_c
    arrived = [i for i, g in c.strips.goal.items() if np.allclose(sw.xy[i], g, atol=1e-6)]
    assert arrived
    for i in arrived:  # on the lattice anchored at the base station
        rows, connectors = strip_goal_points(base, s, sw.xy[i], 1e-6)
        assert len(rows) + len(connectors) == 1


def test_strip_goals_run_keeps_agents_and_routers_connected_on_the_unit_disk():
    s = amronet.run(office(), seed=3).summary
    assert s["routers_deployed"] >= 1
    assert s["routers_connected_fraction"] == 1.0
    assert s["agents_connected_min"] == 1.0
    m = s["mission"]["strip_goals"]
    assert sum(m.values()) >= 1


def test_strip_goals_with_settling_routers_drive_once_they_relay():
    sim = Simulation(office(**{"agents.drop_settle_s": 2.0, "sim.time_limit": 60.0}), seed=2)
    sim.run()
    assert sum(sim.controller.mission_report()["strip_goals"].values()) >= 1
    assert not sim.controller.strips.waiting or all(sim.swarm.state[i] == State.DROPPED
                                                   for i in sim.controller.strips.waiting)


@pytest.mark.parametrize(("building", "radio"), [("hospital_section", "unit-disk"), ("depot", "multi-wall")])
def test_stretches_go_on_while_strip_routers_drive_and_give_the_reference_run(building, radio, monkeypatch):
    """Strip routers on their way are steered in the quiet stretch; one arriving or giving up ends it (Python)."""
    b = BUILDINGS[building]  # (as ``amronet reproduce buildings`` runs it, stock 6)
    sc = amronet.load_scenario(agent_scenario(b.map, b.r_c, (b.base,), 3, "frontier", 100.0, radio=RADIOS[radio],
                                              drop_rule="strip-goals",
                                              agents={"routers_carried": 6, "when_empty": "continue"}))
    stretched, reference = Simulation(sc, 70_001), Simulation(sc, 70_001, step="reference")
    quiet = stretched.compiled.quiet
    assert isinstance(quiet, QuietStretch)
    driving: list[int] = []  # steps taken in stretches that started with a strip router on its way
    take = QuietStretch.take

    def counting(self, *args, **kwargs):
        moving = self.compiled.controller.strips.moving
        out = take(self, *args, **kwargs)
        if out is not None and moving:
            driving.append(out.steps)
        return out

    monkeypatch.setattr(QuietStretch, "take", counting)
    a, b = stretched.run(), reference.run()
    assert sum(driving) > stretched.steps / 4 and quiet.strip_steps == sum(driving)
    assert quiet.ends["triangle"] > 0  # (one base station: no triangle router; strip routers arrived or gave up)
    sw, ref = stretched.swarm, reference.swarm
    for x, y in ((sw.xy, ref.xy), (sw.heading, ref.heading), (sw.state, ref.state), (sw.distance, ref.distance)):
        np.testing.assert_array_equal(x, y)
    mine, theirs = stretched.controller.strips, reference.controller.strips
    assert mine.counts == theirs.counts and mine.tries == theirs.tries and sum(mine.counts.values()) > 0
    assert stretched.rows == reference.rows and a.network == b.network
    assert {k: v for k, v in a.summary.items() if k != "wall_time_s"} == \
        {k: v for k, v in b.summary.items() if k != "wall_time_s"}


@pytest.mark.parametrize(("drop", "field"), [
    ({"spacing": 1.5}, "algorithm.params.drop.spacing"),
    ({"free_radius": 0}, "algorithm.params.drop.free_radius"),
    ({"retries": -1}, "algorithm.params.drop.retries"),
    ({"lattice": "hex"}, "algorithm.params.drop.lattice"),
])
def test_bad_strip_goal_parameters_are_one_line_errors(drop, field):
    with pytest.raises(ScenarioError) as err:
        office(**{"algorithm.params.drop": drop})
    assert err.value.field == field
    assert "\n" not in str(err.value)
