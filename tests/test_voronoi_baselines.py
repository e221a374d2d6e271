"""The Voronoi-cell baselines (VOR, Minimax, Lloyd): their geometry and laws against hand-computed cells,
convergence to a known centroidal Voronoi tessellation, invariants on real maps, and bad parameters."""

import numpy as np
import pytest
import shapely
from scipy.spatial import cKDTree

from amronet.algorithms import ALGORITHMS
from amronet.algorithms.base import AreaKnowledge, Readings, Setup, StepInput
from amronet.algorithms.common.cells import farthest_point, local_cells
from amronet.algorithms.common.polygons import area_centroid, clip_each, regular, to_shapely
from amronet.engine.robots import RobotModel, Role, State, Swarm
from amronet.engine.table import NeighbourTable
from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import Simulation

NAMES = ("vor", "minimax", "lloyd")
FAST = RobotModel("test", radius=0.01, max_speed=1.0, sensor_beams=8, sensor_range=0.1)


def table_of(xy: np.ndarray, r: float) -> NeighbourTable:
    """Every pair within ``r`` (the unit disk), as the radio's table."""
    pairs = np.array(sorted(cKDTree(xy).query_pairs(r)), dtype=np.int64).reshape(-1, 2)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1]])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.lexsort((cols, rows))
    rows, cols = rows[order], cols[order]
    indptr = np.zeros(len(xy) + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=len(xy)), out=indptr[1:])
    return NeighbourTable(xy=xy.copy(), r=r, indptr=indptr, indices=cols.astype(np.int32),
                          dist=np.hypot(*(xy[rows] - xy[cols]).T))


class Harness:
    """A controller driven without the loop: moves exactly as asked, no walls, no bodies, no sensors."""

    def __init__(self, name, xy, r_c, extent, **params):
        xy = np.asarray(xy, dtype=float)
        self.swarm = Swarm.build([(FAST, Role.ROUTER, State.EXPLORE, xy, np.full(len(xy), -1))])
        area = (extent[1] - extent[0]) * (extent[3] - extent[2])
        setup = Setup(robots=self.swarm, r_c=r_c, dt=0.1, rng=np.random.default_rng(0),
                      area=AreaKnowledge(extent, area))
        cls = ALGORITHMS[name]
        self.controller = cls(cls.Params(memory_points=0, **params), setup)
        self.r_c, self.index = r_c, 0

    def step(self):
        sw, dt = self.swarm, 0.1
        command = self.controller.decide(StepInput(self.index, self.index * dt, dt, table_of(sw.xy, self.r_c),
                                                   Readings({})))
        h = sw.heading[command.movers]
        sw.xy[command.movers] += (command.speed * dt)[:, None] * np.stack([np.cos(h), np.sin(h)], axis=1)
        self.controller.after_move(command.movers, np.zeros(len(command.movers), dtype=bool))
        self.index += 1

    def run(self, steps):
        for _ in range(steps):
            self.step()
            if self.controller.settled:
                return True
        return False


# -- geometry -------------------------------------------------------------------------------------------------


def test_clipping_agrees_with_shapely():
    rng = np.random.default_rng(4)
    poly = regular(200, 1.0, 16, 40)
    for _ in range(12):
        angle = rng.uniform(0, 2 * np.pi, 200)
        normal = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        offset = rng.uniform(-0.3, 1.2, 200)
        before = to_shapely(poly)
        poly = clip_each(poly, np.arange(201), normal, offset)
        along = np.stack([-normal[:, 1], normal[:, 0]], axis=1) * 9.0
        edge = normal * offset[:, None]
        halfplane = shapely.polygons(np.stack([edge + along, edge - 9 * normal + along, edge - 9 * normal - along,
                                               edge - along], axis=1))
        expect = shapely.intersection(before, halfplane)
        area, centroid = area_centroid(poly)
        np.testing.assert_allclose(area, shapely.area(expect), atol=1e-12)
        full = shapely.area(expect) > 1e-9
        np.testing.assert_allclose(centroid[full], shapely.get_coordinates(shapely.centroid(expect[full])), atol=1e-9)


def _cells(xy, extent, reach=3.0, vertices=32):
    xy = np.asarray(xy, dtype=float)
    table = table_of(xy, 10.0)
    return local_cells(np.arange(len(xy)), xy, np.ones(len(xy), dtype=bool), table,
                       (np.zeros((len(xy), 0, 2)), np.zeros(len(xy), dtype=np.int64)), extent, reach, vertices)


def test_a_robot_alone_in_a_square_has_the_square_for_its_cell():
    cells = _cells([(0.3, -0.2)], (-1.0, 1.0, -1.0, 1.0))
    area, centroid = area_centroid(cells)
    assert area[0] == pytest.approx(4.0)
    np.testing.assert_allclose(centroid[0], (-0.3, 0.2), atol=1e-12)
    far, vertex = farthest_point(cells, 3.0)
    np.testing.assert_allclose(vertex[0], (-1.3, 1.2), atol=1e-12)  # the corner (-1, 1), relative to the robot
    assert far[0] == pytest.approx(np.hypot(1.3, 1.2))


def test_two_robots_split_a_rectangle_at_their_bisector():
    cells = _cells([(0.3, 0.5), (1.1, 0.5)], (0.0, 2.0, 0.0, 1.0))
    area, centroid = area_centroid(cells)
    np.testing.assert_allclose(area, (0.7, 1.3), atol=1e-12)  # the bisector x = 0.7
    np.testing.assert_allclose(centroid, [(0.05, 0.0), (0.25, 0.0)], atol=1e-12)


def test_a_remembered_wall_point_cuts_the_cell_square_to_the_line_of_sight():
    xy = np.array([(0.0, 0.0)])
    seen = (np.array([[(0.5, 0.0), (-0.3, 0.0)]]), np.array([1]))  # only the first is remembered (filled: 1)
    cells = local_cells(np.array([0]), xy, np.ones(1, dtype=bool), table_of(xy, 1.0), seen, (-1, 1, -1, 1), 3.0, 32)
    area, _ = area_centroid(cells)
    assert area[0] == pytest.approx(1.5 * 2.0)  # x <= 0.5 of the square [-1, 1]^2


def test_the_bounding_disk_bounds_the_cell():
    cells = _cells([(0.0, 0.0)], (-5.0, 5.0, -5.0, 5.0), reach=1.0, vertices=64)
    area, centroid = area_centroid(cells)
    assert area[0] == pytest.approx(0.5 * 64 * np.sin(2 * np.pi / 64))  # the inscribed 64-gon of the unit circle
    np.testing.assert_allclose(centroid[0], 0.0, atol=1e-12)


# -- the laws -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["lloyd", "minimax"])
def test_a_robot_alone_in_a_square_goes_to_its_centre(name):
    h = Harness(name, [(0.3, -0.2)], 3.0, (-1.0, 1.0, -1.0, 1.0), cell_radius_factor=1.0,
                tolerance_factor=1e-4, round_s=1.0)
    assert h.run(200)
    np.testing.assert_allclose(h.swarm.xy[0], (0.0, 0.0), atol=3e-4)


def test_vor_moves_towards_its_farthest_vertex_until_it_would_cover_it():
    h = Harness("vor", [(0.6, -0.6)], 2.0, (-1.0, 1.0, -1.0, 1.0))  # r_s = 1: the corner (-1, 1) is 2.26 away
    h.step()
    v = np.array([-1.0, 1.0]) - (0.6, -0.6)
    expect = (0.6, -0.6) + v / np.hypot(*v) * min(np.hypot(*v) - 1.0, 1.0)  # cut to r_c / 2 = 1
    np.testing.assert_allclose(h.controller.goal[0], expect, atol=1e-12)
    assert h.controller.swarm.state[0] == State.EXPLORE


def test_vor_stays_where_its_move_would_not_cover_more_of_its_cell():
    """Wang et al.'s movement adjustment: from (0.3, -0.2) the move towards (-1, 1) covers no more of the square."""
    h = Harness("vor", [(0.3, -0.2)], 2.0, (-1.0, 1.0, -1.0, 1.0))
    h.step()
    np.testing.assert_array_equal(h.controller.goal[0], (0.3, -0.2))
    assert h.controller.settled
    h = Harness("vor", [(0.3, -0.2)], 2.0, (-1.0, 1.0, -1.0, 1.0), min_gain=0.0)
    h.step()
    assert h.controller.settled  # the move would lose coverage, not merely gain too little


@pytest.mark.parametrize("name", ["lloyd", "minimax"])
def test_two_robots_split_a_rectangle(name):
    holes = {"sensing_radius_factor": 0.15, "min_gain": 0.0} if name == "minimax" else {}  # r_s = 0.45: a hole
    h = Harness(name, [(0.3, 0.5), (1.1, 0.5)], 3.0, (0.0, 2.0, 0.0, 1.0), cell_radius_factor=1.0,
                tolerance_factor=1e-4, round_s=1.0, **holes)
    h.step()  # the first round's goals: the centroids (Lloyd) or minimax points of the two halves
    np.testing.assert_allclose(h.controller.goal, [(0.35, 0.5), (1.35, 0.5)], atol=1e-9)
    assert h.run(2000)
    xy = h.swarm.xy
    if name == "lloyd":  # the centroidal split
        np.testing.assert_allclose(xy, [(0.5, 0.5), (1.5, 0.5)], atol=1e-3)
    else:  # Minimax stops once its move gains nothing: each sensing disk whole within its half
        assert np.hypot(*(xy[1] - xy[0])) >= 2 * 0.45 - 1e-9
        assert (xy[:, 0] >= 0.45 - 1e-9).all() and (xy[:, 0] <= 2 - 0.45 + 1e-9).all()


def test_lloyd_converges_on_an_open_square_to_the_known_cvt():
    rng = np.random.default_rng(7)
    start = np.array([(-0.4, -0.6), (0.6, -0.4), (0.4, 0.6), (-0.6, 0.4)]) + rng.uniform(-0.05, 0.05, (4, 2))
    h = Harness("lloyd", start, 3.0, (-1.0, 1.0, -1.0, 1.0), cell_radius_factor=1.0, tolerance_factor=1e-5,
                round_s=0.5)
    assert h.run(5000)
    np.testing.assert_allclose(h.swarm.xy, [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)], atol=1e-3)


@pytest.mark.parametrize("name", ["vor", "minimax"])
def test_vor_and_minimax_cover_an_open_square_they_can_cover(name):
    """Four sensing disks of radius 0.8 can cover the 2 m square; the hole-driven rules end with it covered."""
    start = np.array([(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)])
    h = Harness(name, start, 1.6, (-1.0, 1.0, -1.0, 1.0), round_s=0.5)
    assert h.run(5000)
    g = np.linspace(-1, 1, 41)
    points = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    nearest = cKDTree(h.swarm.xy).query(points)[0]
    assert nearest.max() <= 0.8 + 1e-6


# -- real maps ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(("preset_map", "overrides"), [
    ("obstacles-6x6", {}),
    ("autolab", {"base_stations": [{"x": 2.5, "y": 10.0}], "radio.r_c": 2.0, "routers.count": 25}),
])
def test_invariants_on_real_maps(name, preset_map, overrides):
    sc = load_scenario(f"{name}-obstacles-6x6", {"map": preset_map, "sim.time_limit": 20.0, **overrides})
    sim = Simulation(sc, 3)
    sw, omap, ctrl = sim.swarm, sim.world.omap, sim.controller
    routers = np.flatnonzero(sw.role == Role.ROUTER)
    for _ in range(200):
        before, states = sw.xy.copy(), sw.state.copy()
        sim.step()
        step = np.hypot(*(sw.xy - before).T)
        assert np.isfinite(sw.xy).all()
        assert (step[routers] <= sw.max_speed[routers] * sim.dt + 1e-9).all()
        assert omap.is_free(sw.xy[routers]).all()
        held = routers[(states[routers] == State.REFERENCE) & (sw.state[routers] == State.REFERENCE)]
        assert (step[held] == 0.0).all()  # a robot without a move stays
        assert (step[sw.role != Role.ROUTER] == 0.0).all()
    assert ctrl.rounds >= 200 // ctrl.round_steps
    if preset_map == "obstacles-6x6":  # 30 routers from the base region meet the obstacles within 20 s
        assert ctrl.memory.stored[routers].sum() > 0


@pytest.mark.parametrize("name", NAMES)
def test_runs_are_reproducible_and_batch_as_they_run_alone(name):
    from amronet.sim.batch import run_seeds

    sc = load_scenario(f"{name}-obstacles-6x6", {"sim.time_limit": 15.0})
    alone = [Simulation(sc, seed).run() for seed in (1, 2)]
    again = Simulation(sc, 1).run()
    batched = run_seeds(sc, [1, 2])
    assert again.files()["network.json"] == alone[0].files()["network.json"]
    for a, b in zip(alone, batched, strict=True):
        assert a.files()["network.json"] == b.files()["network.json"]
        assert a.files()["timeseries.csv"] == b.files()["timeseries.csv"]


# -- bad parameters -------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("name", "field", "value"), [
    ("lloyd", "tolerance_factor", 2.0), ("lloyd", "cell_radius_factor", 0.0), ("vor", "min_gain", -0.1),
    ("minimax", "round_s", float("nan")), ("vor", "disk_vertices", 3), ("minimax", "sensing_radius_factor", 1.5),
    ("lloyd", "sensing_radius_factor", 0.5), ("vor", "memory_points", 2.5),
])
def test_bad_parameters_are_one_line(name, field, value, capsys, tmp_path):
    with pytest.raises(ScenarioError) as err:
        load_scenario(f"{name}-6x6", {f"algorithm.params.{field}": value})
    assert f"algorithm.params.{field}" in str(err.value) and "\n" not in str(err.value)
    from amronet.cli import main

    assert main(["run", "--preset", f"{name}-6x6", "--set", f"algorithm.params.{field}={value}", "-q",
                 "--out", str(tmp_path / "r")]) == 2
    assert not (tmp_path / "r").exists()
    out = capsys.readouterr().err.strip().splitlines()
    assert len(out) == 1 and out[0].startswith("amronet: error: ") and field in out[0]


# -- the parameters' descriptions -----------------------------------------------------------------------------


def test_the_reference_describes_inherited_parameters_from_their_base_class():
    """VOR and Minimax describe only what they add; the scenario reference takes the rest from ``HoleParams``."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
    import docs_reference

    hole = docs_reference._descriptions(ALGORITHMS["vor"].Params.__mro__[1])
    vor = docs_reference._descriptions(ALGORITHMS["vor"].Params)
    minimax = docs_reference._descriptions(ALGORITHMS["minimax"].Params)
    lloyd = docs_reference._descriptions(ALGORITHMS["lloyd"].Params)
    assert vor == hole and set(vor) == set(ALGORITHMS["vor"].Params.model_fields)
    assert minimax == {**hole, "tolerance_factor": minimax["tolerance_factor"]} and "minimax point" in minimax[
        "tolerance_factor"]
    assert "Cortés, Martínez and Bullo" in lloyd["cell_radius_factor"]  # its own, not its base class's
