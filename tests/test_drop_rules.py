"""Drop rules of agent-assisted deployment (issue #19): each rule's trigger, location-free rules, realism switches."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import amronet
from amronet.algorithms.agent_assisted.drops import DROP_RULES, AgentView, DropContext, validate_drop_params
from amronet.algorithms.agent_assisted.drops.junction import PathTurns
from amronet.algorithms.agent_assisted.drops.trail import Trails
from amronet.algorithms.agent_assisted.rule_kernels import path_turning, ring_openings
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.robots import State
from amronet.errors import ScenarioError
from amronet.sim import Simulation
from helpers import box_map

R_C = 4.0
CONTEXT = DropContext(r_c=R_C, r_eff=0.95 * R_C, dt=0.1, n_agents=1, sensor_range=2.0)


def rule(name: str, context: DropContext = CONTEXT, **params):
    cls = DROP_RULES[name]
    return cls(validate_drop_params(cls, params, "algorithm.params.drop"), context)


def view(t=0.0, margin=10.0, xy=(0.0, 0.0), relays=((0.0, 0.0),), bases=((0.0, 0.0),), current=0, nearest=1.0,
         contact=True, scans=None, can_drop=True) -> AgentView:
    return AgentView(t=t, current=np.array([current]), nearest_d=np.array([nearest]), best_margin=np.array([margin]),
                     xy=np.array([xy], dtype=float), heading=np.zeros(1), relay_xy=np.array(relays, dtype=float),
                     base_xy=np.array(bases, dtype=float), in_contact=np.array([contact]),
                     scans=None if scans is None else np.array([scans], dtype=float), can_drop=np.array([can_drop]))


# -- link-quality -------------------------------------------------------------------------------------------------
def test_link_quality_needs_a_sustained_weak_link_or_a_breaking_one():
    lq = rule("link-quality", drop_margin_db=3.0, loss_margin_db=1.0, smoothing_s=0.5)
    margins = [10.0] * 20 + [2.0]  # one faded sample between the two thresholds
    fired = [bool(lq.decide(view(t=0.1 * k, margin=m))[0]) for k, m in enumerate(margins)]
    assert not any(fired)
    fired = [bool(lq.decide(view(t=2.1 + 0.1 * k, margin=2.0))[0]) for k in range(30)]  # sustained: fires later
    assert not fired[0] and any(fired)
    lq = rule("link-quality", drop_margin_db=3.0, loss_margin_db=1.0, smoothing_s=0.5)
    lq.decide(view(t=0.0, margin=10.0))
    assert lq.decide(view(t=0.1, margin=0.5))[0]  # below the loss threshold: at once


def test_link_quality_drops_nothing_without_a_reference_or_a_router():
    lq = rule("link-quality")
    assert not lq.decide(view(t=0.0, margin=-np.inf))[0]
    assert not lq.decide(view(t=0.1, margin=0.0, can_drop=False))[0]
    assert lq.losing(view(t=0.1, margin=0.0, can_drop=False))[0]  # a tethered agent turns back there


@settings(max_examples=40, deadline=None)
@given(margins=st.lists(st.floats(-5, 30), min_size=1, max_size=40),
       shift=st.tuples(st.floats(-50, 50), st.floats(-50, 50)), nearest=st.floats(0.01, 10))
def test_link_quality_reads_no_positions(margins, shift, nearest):
    """Perturbed positions and distances, the same radio: the same decisions, step by step."""
    a, b = rule("link-quality"), rule("link-quality")
    for k, m in enumerate(margins):
        plain = view(t=0.1 * k, margin=m)
        moved = view(t=0.1 * k, margin=m, xy=shift, relays=((shift[1], shift[0]), (3.0, -7.0)), bases=((9.0, 9.0),),
                     nearest=nearest, current=5)
        assert a.decide(plain)[0] == b.decide(moved)[0]
        assert a.losing(plain)[0] == b.losing(moved)[0]


def test_a_wall_kills_the_link_before_the_distance_rule_fires_but_not_before_the_link_quality_rule():
    """An agent walks away from its reference across a wall at 0.8 r_c (multi-wall radio, 6.9 dB per wall)."""
    omap = box_map(rows=40, cols=200, res=0.05, walls=[(slice(1, 39), slice(90, 92))])  # wall at x = 4.5-4.6 m
    r_c = 5.0
    medium = make_medium("multi-wall", LinkBudget(r_c=r_c, exponent=2.0, wall_db=6.9), omap=omap)
    ref = np.array([0.5, 1.0])
    context = DropContext(r_c=r_c, r_eff=0.95 * r_c, dt=0.1, n_agents=1, sensor_range=2.0)
    last_ref = rule("last-reference", context)
    lq = rule("link-quality", context, drop_margin_db=3.0)  # less than the margin left at the wall
    fired = {"last-reference": None, "link-quality": None}
    lost_at = None
    for k, x in enumerate(np.arange(0.8, 9.0, 0.05)):
        table = medium.update(np.array([ref, [x, 1.0]]))
        heard = table.indptr[2] > table.indptr[1]
        if not heard and lost_at is None:
            lost_at = x
        margin = float(table.margin[table.indptr[1]]) if heard else -np.inf
        d = float(table.dist[table.indptr[1]]) if heard else np.inf
        v = view(t=0.1 * k, margin=margin, xy=(x, 1.0), relays=(ref,), current=0 if heard else -1, nearest=d)
        for name, r in (("last-reference", last_ref), ("link-quality", lq)):
            if fired[name] is None and r.decide(v)[0]:
                fired[name] = x
    assert lost_at is not None and lost_at < 0.95 * r_c  # the wall, not the distance, ends the link
    assert fired["last-reference"] is None  # the paper's rule never saw it coming
    assert fired["link-quality"] is not None and fired["link-quality"] < lost_at


# -- distance-junction (MARBLE) ----------------------------------------------------------------------------------
def test_openings_of_a_room_a_corridor_and_a_junction():
    closed, far = 0.5, 2.0
    room = [far] * 16
    corridor = [far] + [closed] * 7 + [far] + [closed] * 7
    tee = [far, far] + [closed] * 3 + [far, far] + [closed] * 4 + [far, far] + [closed] * 3
    dead_end = [closed] * 16
    got = [ring_openings(np.array(ring, dtype=float), 0.95 * far) for ring in (room, corridor, tee, dead_end)]
    assert got == [1, 2, 3, 0]


def test_path_turns_are_seen_on_corners_not_on_straight_lines():
    turns = PathTurns(2, travel=1.0, angle_deg=30.0)
    seen = np.zeros(2, dtype=bool)
    for k in range(40):
        s = 0.05 * k
        straight = (s, 0.0)
        corner = (s, 0.0) if s <= 1.0 else (1.0, s - 1.0)
        samples, new, spacing, cos_angle = turns.books()
        for m, (x, y) in enumerate((straight, corner)):
            seen[m] |= path_turning(m, x, y, samples, new, spacing, cos_angle)
        samples[...] = new
    assert seen.tolist() == [False, True]


def test_distance_junction_rules():
    ctx = DropContext(r_c=10.0, r_eff=9.5, dt=0.1, n_agents=1, sensor_range=2.0)
    tee = [2.0, 2.0] + [0.5] * 3 + [2.0, 2.0] + [0.5] * 4 + [2.0, 2.0] + [0.5] * 3
    corridor = [2.0] + [0.5] * 7 + [2.0] + [0.5] * 7
    base = ((0.0, 0.0),)

    def fires(xy, relays, scans, contact=True):
        return bool(rule("distance-junction", ctx).decide(view(xy=xy, relays=relays, bases=base, scans=scans,
                                                               contact=contact))[0])

    assert fires((9.2, 0.0), base, corridor)  # farther than 0.9 r_c from every relay
    assert not fires((9.2, 0.0), base, corridor, contact=False)  # only while in contact
    assert not fires((8.0, 0.0), base, corridor)  # nothing to say in a corridor at 8 m
    assert fires((8.0, 0.0), base, tee)  # a junction, no relay within 0.3 r_c
    assert not fires((8.0, 0.0), ((0.0, 0.0), (6.0, 0.0)), tee)  # a relay within 3 m of the junction
    assert not fires((2.0, 0.0), base, tee)  # never within 0.3 r_c of the base


def test_radius_rule_and_its_timer():
    r = rule("radius", radius=0.5)
    assert not r.decide(view(xy=(1.9, 0.0)))[0]
    assert r.decide(view(xy=(2.1, 0.0)))[0]
    timed = rule("radius", radius=0.5, every_s=5.0)
    assert not timed.decide(view(t=4.9, xy=(1.0, 0.0)))[0]
    assert timed.decide(view(t=5.0, xy=(1.0, 0.0)))[0]
    timed.dropped(np.array([True]), view(t=5.0))
    assert not timed.decide(view(t=9.0, xy=(1.0, 0.0)))[0]


def test_trails_lead_back_along_the_path():
    trails = Trails(np.zeros((1, 2)), spacing=0.5)
    path = [(0.1 * k, 0.0) for k in range(21)] + [(2.0, 0.1 * k) for k in range(1, 21)]
    for p in path:
        trails.update(np.array([p]), np.array([True]))
    first = trails.back(0, np.array([2.0, 2.0]))
    assert first is not None and np.allclose(first, (2.0, 1.5))
    p = np.array([2.0, 2.0])
    visited = []
    while (target := trails.back(0, p)) is not None:
        visited.append(target.copy())
        p = target
    assert np.allclose(visited[-1], (0.0, 0.0)) and any(np.allclose(v, (2.0, 0.0)) for v in visited)


# -- the rules inside runs --------------------------------------------------------------------------------------
def office(**overrides):
    base = {"sim.time_limit": 60.0, "algorithm.params.explorer": "frontier"}
    return amronet.load_scenario("agent-assisted-office", overrides={**base, **overrides})


@pytest.mark.parametrize("name", ["last-reference", "link-quality", "radius", "distance-junction"])
def test_every_rule_deploys_and_keeps_agents_connected_on_the_unit_disk(name):
    result = amronet.run(office(**{"algorithm.params.drop_rule": name}), seed=2)
    s = result.summary
    assert s["routers_deployed"] >= 1
    assert s["agents_connected_min"] == 1.0  # tethered when needed, and every rule drops in time on the disk
    assert s["routers_connected_fraction"] == 1.0


def test_link_quality_keeps_agents_connected_better_than_the_distance_rule_under_walls():
    walls = {"radio.model": "multi-wall", "sim.time_limit": 150.0}
    paper = amronet.run(office(**walls), seed=1).summary
    lq = amronet.run(office(**walls, **{"algorithm.params.drop_rule": "link-quality"}), seed=1).summary
    assert lq["agents_connected_fraction"] > paper["agents_connected_fraction"]


def test_dropped_routers_settle_before_they_relay():
    sim = Simulation(office(**{"agents.drop_settle_s": 3.0}), seed=2)
    seen_dropped_at = None
    for _ in range(600):
        sim.step()
        dropped = np.flatnonzero(sim.swarm.state == State.DROPPED)
        if len(dropped) and seen_dropped_at is None:
            seen_dropped_at, router = sim.t, int(dropped[0])
            assert not sim.swarm.relaying[router] and not sim.swarm.deployed[router]
        if seen_dropped_at is not None and sim.t >= seen_dropped_at + 3.1:
            break
    assert seen_dropped_at is not None
    assert sim.swarm.state[router] == State.REFERENCE and sim.swarm.relaying[router]


def test_an_agent_out_of_routers_is_cut_off_when_it_continues_and_never_when_tethered():
    stock = {"agents.routers_carried": 1, "sim.time_limit": 120.0}
    tethered = amronet.run(office(**stock), seed=3).summary
    going_on = amronet.run(office(**stock, **{"agents.when_empty": "continue"}), seed=3).summary
    assert tethered["agents_connected_min"] == 1.0
    assert going_on["agents_connected_min"] < 1.0


def test_reverse_drop_backs_agents_into_contact_under_walls():
    walls = {"radio.model": "multi-wall", "sim.time_limit": 200.0, "agents.reverse_drop": 1.0}
    sim = Simulation(office(**walls), seed=1)
    sim.run()
    assert sim.controller.mission_report()["reverse_drops"] >= 1


# -- parameters ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("overrides", "field"), [
    ({"algorithm.params.drop_rule": "nearest"}, "algorithm.params.drop_rule"),
    ({"algorithm.params.drop_rule": "link-quality", "algorithm.params.drop": {"drop_margin_db": 1.0}},
     "algorithm.params.drop"),
    ({"algorithm.params.drop_rule": "link-quality", "algorithm.params.drop": {"margin": 1.0}},
     "algorithm.params.drop.margin"),
    ({"algorithm.params.drop_rule": "radius", "algorithm.params.drop": {"radius": -1}},
     "algorithm.params.drop.radius"),
    ({"agents.drop_settle_s": -1.0}, "agents.drop_settle_s"),
    ({"agents.when_empty": "explode"}, "agents.when_empty"),
    ({"agents.reverse_drop": 0}, "agents.reverse_drop"),
])
def test_bad_drop_parameters_are_one_line_errors(overrides, field):
    with pytest.raises(ScenarioError) as err:
        amronet.load_scenario("agent-assisted-office", overrides=overrides)
    assert err.value.field == field
    assert "\n" not in str(err.value)


def test_bad_drop_rule_on_the_command_line_exits_2(tmp_path, capsys):
    from amronet.cli.main import main

    code = main(["run", "--preset", "agent-assisted-office", "--out", str(tmp_path / "r"),
                 "--set", "algorithm.params.drop_rule=nearest"])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "algorithm.params.drop_rule" in err
    assert not (tmp_path / "r").exists()
