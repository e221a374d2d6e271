"""Quiet stretches of agent-assisted runs under the path-loss radio and the link-quality rule, against the same runs
step by step (amronet.algorithms.agent_assisted.stretch_links)."""

import numpy as np
import pytest

from amronet.algorithms.agent_assisted.stretch import QuietStretch
from amronet.algorithms.agent_assisted.stretch_links import NO_MARGIN, Radio, next_radio
from amronet.engine.radio import make_medium
from amronet.experiments.building_cells import BUILDINGS, RULES
from amronet.experiments.common import agent_scenario
from amronet.scenario import load_scenario
from amronet.scenario.radio_spec import RadioSpec
from amronet.sim import Simulation
from amronet.world.builtin import resolve_map
from test_agent_stretch import _books, _summary

CASES = {  # name: (building, drop rule, radio fields, agents fields, simulated seconds)
    **{f"{b}, {rule}, multi-wall {db} dB": (b, rule, {"model": "multi-wall", "shadowing_db": db}, {}, 150.0)
       for b in ("hospital_section", "office-32x32") for db in (0.0, 4.0)
       for rule in ("last-reference", "radius", "distance-junction", "link-quality")},
    "office-32x32, link-quality, unit disk": ("office-32x32", "link-quality", {}, {}, 200.0),
    "hospital_section, link-quality, unit disk": ("hospital_section", "link-quality", {}, {}, 150.0),
    "office-32x32, link-quality, log-distance": ("office-32x32", "link-quality", {"model": "log-distance"}, {}, 150.0),
    "hospital_section, radius, 3 routers then on": (
        "hospital_section", "radius", {"model": "multi-wall", "shadowing_db": 4.0},
        {"routers_carried": 3, "when_empty": "continue"}, 200.0),
    "office-32x32, link-quality, 6 routers then on": (
        "office-32x32", "link-quality", {"model": "multi-wall", "shadowing_db": 4.0},
        {"routers_carried": 6, "when_empty": "continue"}, 200.0),
}


def _scenario(building, rule, radio, agents, seconds):
    b = BUILDINGS[building]
    name, drop = RULES[rule]
    return load_scenario(agent_scenario(b.map, b.r_c, (b.base,), 3, "frontier", seconds, radio=radio,
                                        drop_rule=name, drop=drop, agents=agents))


@pytest.mark.parametrize("name", sorted(CASES))
def test_stretches_under_the_path_loss_radio_give_the_step_by_step_run_bit_for_bit(name):
    sc = _scenario(*CASES[name])
    fast, slow = Simulation(sc, 7), Simulation(sc, 7)
    assert isinstance(fast.compiled.quiet, QuietStretch)
    slow.compiled.quiet = None
    a, b = fast.run(), slow.run()
    for key, value in _books(slow).items():
        np.testing.assert_array_equal(_books(fast)[key], value, err_msg=key)
    np.testing.assert_array_equal(fast.table.margin, slow.table.margin)
    np.testing.assert_array_equal(fast.table.geometric.indices, slow.table.geometric.indices)
    assert fast.rows == slow.rows
    assert _summary(a) == _summary(b)
    assert sum(fast.compiled.quiet.ends.values()) > 0  # stretches ran
    assert fast.compiled.quiet.laws == (sc.radio.model != "unit-disk")  # (links decided by their margins)


def test_a_stretch_leaves_the_radio_where_its_own_steps_leave_it():
    # the table after a stretch under walls and shadowing, its dropped links and the margins the next step reuses
    sc = _scenario("hospital_section", "distance-junction", {"model": "multi-wall", "shadowing_db": 4.0}, {}, 150.0)
    fast, slow = Simulation(sc, 3), Simulation(sc, 3)
    slow.compiled.quiet = None
    dropped = 0
    while fast.steps < 600:
        fast.advance(40)
        slow.advance(40)
        for t, u in ((fast.table, slow.table), (fast.table.geometric, slow.table.geometric)):
            for key in ("xy", "indptr", "indices", "dist", "margin"):
                np.testing.assert_array_equal(getattr(t, key), getattr(u, key), err_msg=key)
        for k in range(4):
            np.testing.assert_array_equal(fast.medium._previous[k], slow.medium._previous[k])
        dropped += fast.table.candidates is not None
    assert sum(fast.compiled.quiet.ends.values()) > 0 and dropped > 0


def test_only_the_path_loss_law_without_packet_loss_builds_its_tables_in_a_stretch():
    omap = resolve_map("office-32x32")
    rng = np.random.default_rng(1)
    assert make_medium("unit-disk", 4.0, omap, rng).stretch_inputs is not None
    assert make_medium("multi-wall", 4.0, omap, rng).stretch_inputs is not None
    assert make_medium("multi-wall", 4.0, omap, rng, packet_loss=True).stretch_inputs is None
    assert make_medium("unit-disk", 4.0, omap, rng, packet_loss=True).stretch_inputs is None


@pytest.mark.parametrize("margins", [False, True])
@pytest.mark.parametrize(("model", "db"), [("unit-disk", 0.0), ("multi-wall", 0.0), ("multi-wall", 4.0)])
def test_the_stretchs_tables_drop_the_silent_nodes_links_as_the_radio_does(model, db, margins):
    # step after step from one table, some robots moving, a few failed (or none): links, their margins and the
    # geometric view as RadioMedium.update builds them with its silent
    omap = resolve_map("office-32x32")
    rng = np.random.default_rng(11)
    n = 60
    xy = rng.uniform(2.0, 30.0, (n, 2))
    for silent in (np.zeros(n, dtype=bool), rng.random(n) < 0.15):
        budget = RadioSpec(model=model, r_c=6.0, shadowing_db=db).link_budget()
        medium = make_medium(model, budget, omap, np.random.default_rng(3))
        laws = model != "unit-disk"
        table = medium.update(xy, None, silent)
        near = table.geometric
        radio = tuple(Radio(medium.reach, table.indptr, table.indices, table.dist,
                            table.margin if margins else NO_MARGIN, near.indptr, near.indices, near.dist, near.xy,
                            near.link_margin if laws else NO_MARGIN, medium.stretch_inputs,
                            silent if silent.any() else np.zeros(0, dtype=bool)))
        here = xy.copy()
        dropped = 0
        for _ in range(6):
            moving = rng.random(n) < 0.3
            here[moving] += rng.normal(0.0, 0.6, (int(moving.sum()), 2))
            ok, radio = next_radio(here, radio, np.zeros(n, dtype=np.int64), margins)
            table = medium.update(here, None, silent)
            assert ok
            for k, got in ((1, table.indptr), (2, table.indices), (3, table.dist), (5, table.geometric.indptr),
                           (6, table.geometric.indices), (7, table.geometric.dist)):
                np.testing.assert_array_equal(radio[k], got, err_msg=str(k))
            if margins:
                np.testing.assert_array_equal(radio[4], table.margin)
            dropped += len(table.indices) < len(table.geometric.indices)
        if silent.any() or db:  # (links were dropped: the links are not the geometric table)
            assert dropped == 6
