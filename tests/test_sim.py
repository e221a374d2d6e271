"""The loop (amronet.sim.loop), a run's books (amronet.sim.run) and what controllers are given."""

import numpy as np
import pytest

from amronet.algorithms import AreaKnowledge, Setup
from amronet.errors import AmronetError, ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import BatchSimulation, Simulation
from amronet.sim.bench import BASE_SPACING_M, _spaced_bases
from amronet.sim.loop import Loop
from amronet.world.builtin import resolve_map


def scenario(algorithm="self-spreading", **overrides):
    return load_scenario({"map": "obstacles-6x6", "base_stations": [{"x": 0, "y": 0}],
                          "algorithm": {"name": algorithm}, "routers": {"count": 12},
                          "radio": {"r_c": 1.0}, "sim": {"time_limit": 3, "record_every": 5}}, overrides=overrides)


def test_a_simulation_is_the_loop_with_one_run():
    sim = Simulation(scenario(), 4)
    assert isinstance(sim, Loop) and len(sim.runs) == 1 and sim.books is sim.runs[0]
    assert sim.groups is None and sim.books.swarm is sim.swarm and sim.books.table is sim.table


@pytest.mark.parametrize(("step", "phases"), [("reference", {"sense", "decide", "move", "radio"}),
                                              ("compiled", {"sense+decide+move", "radio"})])
def test_step_advances_time_and_every_phase(step, phases):
    sim = Simulation(scenario(), 1, step=step)
    xy = sim.swarm.xy.copy()
    for _ in range(5):
        sim.step()
    assert sim.steps == 5 and sim.t == pytest.approx(0.5)
    assert set(sim.phase_seconds) == phases
    assert all(v > 0 for v in sim.phase_seconds.values())
    assert not np.array_equal(xy, sim.swarm.xy)
    np.testing.assert_array_equal(sim.table.xy, sim.swarm.xy)  # the radio ran on the new positions


def test_a_time_limited_run_is_truncated_and_recorded_every_k_steps():
    result = Simulation(scenario(), 2).run()
    s = result.summary
    assert s["stop_reason"] == "time_limit" and s["truncated"] and not s["terminated"]
    assert s["steps"] == 30 and s["sim_time_s"] == pytest.approx(3.0)
    assert result.timeseries["t"].tolist() == pytest.approx([0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0])


def test_a_run_that_settles_terminates_and_says_since_when():
    sc = scenario(**{"routers.count": 2, "sim.time_limit": 200})
    result = Simulation(sc, 3).run()
    s = result.summary
    assert s["stop_reason"] == "settled" and s["terminated"]
    assert s["settled_at_s"] == pytest.approx(s["sim_time_s"])
    assert result.timeseries["t"][-1] == pytest.approx(s["sim_time_s"])  # the last step is recorded


def test_a_coverage_target_met_at_the_start_ends_the_run_at_once():
    sc = scenario(**{"sim.coverage_target": 0.01})
    result = Simulation(sc, 1).run()
    assert result.summary["stop_reason"] == "coverage_target" and result.summary["steps"] == 0


@pytest.mark.parametrize("seed", [-1, 2**63, 1.5, True, "3"])
def test_bad_seeds_are_refused_naming_the_field(seed):
    with pytest.raises(ScenarioError, match=r"^seed: "):
        Simulation(scenario(), seed)


def test_a_batch_run_that_ends_keeps_its_own_robots_while_the_others_go_on():
    sc = scenario(**{"sim.time_limit": 20, "sim.coverage_target": 0.3})
    batch = BatchSimulation(sc, [1, 2, 3])
    results = batch.run()
    ends = [r.summary["steps"] for r in results]
    assert len(set(ends)) > 1, "the seeds should stop at different steps for this test to mean something"
    first = int(np.argmin(ends))
    frozen = results[first].run.swarm
    assert frozen.xy.base is None or frozen.xy.base is not batch.swarm.xy  # a copy, not a view
    alone = Simulation(sc, [1, 2, 3][first]).run()
    np.testing.assert_array_equal(alone.run.swarm.xy, frozen.xy)


def test_controllers_get_a_setup_without_map_or_scenario():
    sim = Simulation(scenario(), 1)
    ctl = sim.controller
    for name in ("omap", "scenario", "world", "table"):
        assert not hasattr(ctl, name)
    omap = sim.world.omap
    assert ctl.area == AreaKnowledge(extent=omap.extent,
                                     free_area_m2=float(np.count_nonzero(omap.free)) * omap.resolution**2)
    assert set(Setup.__dataclass_fields__) == {"robots", "r_c", "dt", "rng", "area", "stock", "paths",
                                               "links_by_distance"}


def test_agents_get_their_stock_and_a_hand_that_checks_the_floor():
    sc = load_scenario("agent-assisted-office", overrides={"agents.routers_carried": 4, "sim.time_limit": 1})
    sim = Simulation(sc, 1)
    ctl = sim.controller
    assert ctl.left[sim.agents].tolist() == [4.0] * len(sim.agents)
    assert ctl.router_model.name == "bebot"
    omap = sim.world.omap
    wall = np.argwhere(~omap.free)[0]
    inside = np.array([omap.origin[0] + (wall[1] + 0.5) * omap.resolution,
                       omap.origin[1] + (omap.cells.shape[0] - wall[0] - 0.5) * omap.resolution])
    start = sim.swarm.xy[sim.agents[:1]]
    assert ctl.path_clear(start, start, np.array([0.045])).all()
    assert not ctl.path_clear(inside[None], inside[None], np.array([0.045])).any()


def test_the_loop_asks_controllers_through_their_declared_interface():
    from amronet.algorithms import ALGORITHMS

    ss, aa, dssa = ALGORITHMS["self-spreading"], ALGORITHMS["agent-assisted"], ALGORITHMS["dssa"]
    assert ss.start_range(ss.Params(loss_margin=0.1), 2.0) == pytest.approx(1.8)
    assert dssa.start_range(dssa.Params(), 2.0) == pytest.approx(1.9)
    assert aa.default_coverage_target == 0.99 and ss.default_coverage_target is None
    sim = Simulation(scenario("dssa"), 1)
    assert sim.controller.unsettled().sum() == 12 and not sim.controller.settled


def test_bench_base_stations_are_spaced_apart_or_refused():
    """``amronet bench`` draws a base station per 1 000 robots: never two whose reference nodes would overlap."""
    omap = resolve_map("open-6x6")
    rows, cols = np.nonzero(omap.free)
    bases = _spaced_bases(omap, rows, cols, 40, np.random.default_rng(1))
    assert bases.shape == (40, 2)
    gaps = np.linalg.norm(bases[:, None] - bases[None], axis=-1) + np.eye(40) * 1e9
    assert gaps.min() >= BASE_SPACING_M
    with pytest.raises(AmronetError, match="--robots: the map has no room for 400 base stations"):
        _spaced_bases(omap, rows, cols, 400, np.random.default_rng(1))  # 36 m² hold about 100
