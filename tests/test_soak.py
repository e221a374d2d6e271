"""The soak of issue #18 (``tools/soak.py``): a 40-scenario slice, and its checker against planted violations."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from amronet.engine.robots import Role, State
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from helpers import box_map

ROOT = Path(__file__).resolve().parents[1]
SOAK = ROOT / "tools" / "soak.py"

SLICE_SEED = 18
SLICE_COUNT = 40
SLICE_TIME_LIMIT = 20.0
"""Simulated seconds a slice scenario may run at most (each draws its own from 3 s up): about 30 s on two cores."""


@pytest.fixture(scope="module")
def soak():
    spec = importlib.util.spec_from_file_location("amronet_soak_tool", SOAK)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def test_soak_slice_has_no_failures(tmp_path):
    """40 random scenarios over every map, algorithm and radio model: no crash, hang or failing violation."""
    report = tmp_path / "soak.json"
    proc = subprocess.run(
        [sys.executable, str(SOAK), "--count", str(SLICE_COUNT), "--seed", str(SLICE_SEED), "--jobs", "2",
         "--time-limit", str(SLICE_TIME_LIMIT), "--timeout", "240", "--out", str(report)],
        cwd=ROOT, capture_output=True, text=True, timeout=1200,
    )
    print(proc.stdout[-20000:])
    print(proc.stderr[-5000:], file=sys.stderr)
    assert report.is_file(), "the soak wrote no report"
    assert proc.returncode == 0, "the soak found failures; each is printed above with the command that replays it"


def test_draws_are_reproducible_one_by_one(soak):
    a, seed_a = soak.draw_scenario(5, 7, max_time=20.0)
    b, seed_b = soak.draw_scenario(5, 7, max_time=20.0)
    assert a == b and seed_a == seed_b
    assert soak.draw_scenario(5, 8, max_time=20.0)[0] != a
    # scenario i is the i-th child of numpy.random.default_rng(seed), whatever else is drawn
    child = np.random.default_rng(5).spawn(8)[7]
    assert child.random() == soak.scenario_rng(5, 7).random()
    assert 3.0 <= a["sim"]["time_limit"] <= 20.0
    load_scenario(a)  # plain data that validates


def test_draws_cover_every_map_algorithm_and_radio(soak):
    draws = [soak.draw_scenario(1, i, max_time=10.0)[0] for i in range(120)]
    from amronet.algorithms import ALGORITHMS
    from amronet.engine.radio import MEDIA
    from amronet.world.builtin import BUILTIN_MAPS
    assert {d["map"] for d in draws} == set(BUILTIN_MAPS)
    assert {d["algorithm"]["name"] for d in draws} == set(ALGORITHMS)
    assert {d["radio"]["model"] for d in draws} == set(MEDIA)
    assert {len(d["base_stations"]) for d in draws} == {1, 2, 3, 4}


def test_wall_depth_is_exact_against_a_slow_reference(soak):
    omap = box_map(rows=40, cols=50, res=0.05, origin=(-1.0, -0.5),
                   walls=[(slice(10, 12), slice(5, 30)), (slice(20, 35), slice(33, 34))])
    rng = np.random.default_rng(3)
    xmin, xmax, ymin, ymax = omap.extent
    xy = np.c_[rng.uniform(xmin - 0.2, xmax + 0.2, 400), rng.uniform(ymin - 0.2, ymax + 0.2, 400)]
    radius = rng.uniform(0.01, 0.3, 400)
    rows, cols = np.nonzero(omap.blocked)
    x0 = omap.origin[0] + cols * omap.resolution
    y0 = omap.origin[1] + rows * omap.resolution
    got = soak.wall_depth(omap, xy, radius)
    for (px, py), r, depth in zip(xy, radius, got, strict=True):
        dx = np.maximum(np.maximum(x0 - px, px - (x0 + omap.resolution)), 0.0)
        dy = np.maximum(np.maximum(y0 - py, py - (y0 + omap.resolution)), 0.0)
        off_map = max(min(px - xmin, xmax - px, py - ymin, ymax - py), 0.0)
        ref = r - min(float(np.hypot(dx, dy).min()), off_map)
        if ref > -omap.resolution:  # the window sees every blocked cell that could touch the body
            assert depth == pytest.approx(ref, abs=1e-12)
        else:
            assert depth < 0


def test_checker_finds_planted_violations(soak):
    scenario = {"map": "open-6x6", "radio": {"r_c": 1.0},
                "base_stations": [{"x": 0.0, "y": 0.0, "region": [1.0, 1.0]}],
                "routers": {"count": 6}, "sim": {"time_limit": 5.0}}
    sim = Simulation(load_scenario(scenario), 1)
    checker = soak.Checker(sim, {"algorithm": {"name": "self-spreading"}})
    checker.geometry()
    checker.network()
    checker.coverage()
    assert checker.findings == {}
    start = sim.swarm.xy.copy()
    sim.swarm.xy[-1] = (2.95, 0.0)
    checker.geometry()
    assert list(checker.findings) == ["body_in_wall_at_start"]  # before the first step: the start placement's
    sim.swarm.xy[:] = start
    checker.findings.clear()
    sim.step()
    sw = sim.swarm
    routers = np.flatnonzero(sw.role == Role.ROUTER)
    sw.xy[routers[0]] = (2.95, 0.0)              # 45 mm body, 30 mm from the border cells' face at 2.98
    sw.xy[routers[1]] = sw.xy[routers[2]] + 0.01  # two bodies on top of each other
    sw.xy[routers[3]] = (2.5, 2.5)
    sw.state[routers[3]] = State.REFERENCE        # deployed, 3.5 m from the base node with r_c = 1 m
    sim.table = sim.medium.update(sw.xy)
    checker.geometry()
    checker.network()
    found = checker.findings
    assert found["body_in_wall"].worst == pytest.approx(0.015, abs=1e-9)
    assert found["bodies_overlap"].worst > 0.07
    assert found["router_cut_off"].worst == 1 and not found["router_cut_off"].known
    sw.xy[routers[4]] = (2.99, 0.0)  # centre in the border
    checker.geometry()
    assert "centre_not_free" in checker.findings


def test_replay_command_names_the_scenario(soak):
    cmd = soak.replay_command(7, 12, 20.0)
    assert "tools/soak.py --replay 12 --seed 7 --time-limit 20" in cmd
    assert "--time-limit" not in soak.replay_command(7, 12, 60.0)
