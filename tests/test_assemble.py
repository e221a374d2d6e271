"""Tests of amronet.sim.assemble: robot kinds from a scenario, the scenario's map, the world and the start swarm."""

from __future__ import annotations

import functools
import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from amronet.engine.robots import AMIGOBOT, BEBOT, PIONEER, ROBOT_MODELS, RobotModel, Role, State
from amronet.errors import MapError, ScenarioError
from amronet.scenario import RobotSpec, Scenario, load_scenario
from amronet.sim.assemble import World, build_swarm, build_world, load_scenario_map, robot_model
from amronet.world.occupancy import UNKNOWN
from amronet.world.space import clearance
from helpers import box_map, diagonal_wall_map

ROW_FIELDS = ("xy", "heading", "role", "state", "status", "radius", "max_speed", "model", "distance")
TINY_BASE = {"radius": 0.01, "max_speed": 0.0, "sensor_beams": 1, "sensor_range": 0.1}
R_START = 1.0


def scenario(**fields: Any) -> Scenario:
    data: dict[str, Any] = {"map": "open-6x6", "base_stations": [{"x": 0.0, "y": 0.0}], "routers": {"count": 10}}
    data.update(fields)
    return load_scenario(data)


def one_line_error(excinfo: pytest.ExceptionInfo[ScenarioError], field: str) -> ScenarioError:
    exc = excinfo.value
    assert exc.field == field
    assert "\n" not in str(exc)
    assert str(exc).startswith(f"{field}: ")
    return exc


# --- robot_model -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(ROBOT_MODELS))
def test_robot_kind_by_name_is_the_registered_kind(name: str) -> None:
    assert robot_model(name, "routers.robot") is ROBOT_MODELS[name]


def test_robot_kind_field_by_field() -> None:
    spec = RobotSpec(radius=0.07, max_speed=0.35, sensor_beams=6, sensor_range=0.3)
    assert robot_model(spec, "routers.robot") == RobotModel("custom", 0.07, 0.35, 6, 0.3)


def test_robot_kind_field_by_field_from_a_scenario() -> None:
    sc = scenario(routers={"count": 1, "robot": {"radius": 0.05, "max_speed": 0.1, "sensor_beams": 8,
                                                  "sensor_range": 0.2}})
    kind = robot_model(sc.routers.robot, "routers.robot")
    assert (kind.radius, kind.max_speed, kind.sensor_beams, kind.sensor_range) == (0.05, 0.1, 8, 0.2)


def test_unknown_robot_name_names_the_field_and_the_choices() -> None:
    with pytest.raises(ScenarioError) as excinfo:
        robot_model("roomba", "agents.robot")
    exc = one_line_error(excinfo, "agents.robot")
    assert "'roomba'" in exc.message
    for name in ROBOT_MODELS:
        assert name in exc.message
    assert exc.__cause__ is None and exc.__suppress_context__


def test_robot_names_are_case_sensitive() -> None:
    with pytest.raises(ScenarioError, match="unknown robot 'Bebot'"):
        robot_model("Bebot", "routers.robot")


# --- load_scenario_map ------------------------------------------------------------------------------------

MAP_YAML = (
    "image: {image}\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
    "free_thresh: 0.196\n"
)


def write_tiny_map(folder: Path, name: str = "tiny", **yaml_values: str) -> Path:
    """A 3 m x 2 m map: 30 x 20 pixels at 0.1 m, black border, a full black wall at column 15."""
    folder.mkdir(parents=True, exist_ok=True)
    pixels = np.full((20, 30), 254, dtype=np.uint8)
    pixels[0, :] = pixels[-1, :] = pixels[:, 0] = pixels[:, -1] = 0
    pixels[:, 15] = 0
    Image.fromarray(pixels).save(folder / f"{name}.pgm")
    text = MAP_YAML.format(image=f"{name}.pgm")
    for key, value in yaml_values.items():
        text = "\n".join(line for line in text.splitlines() if not line.startswith(f"{key}:")) + f"\n{key}: {value}\n"
    path = folder / f"{name}.yaml"
    path.write_text(text)
    return path


def write_scenario(folder: Path, map_ref: str, x: float = 0.75, y: float = 1.0) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "scenario.yaml"
    path.write_text(f"map: {map_ref}\nbase_stations: [{{x: {x}, y: {y}}}]\nrouters: {{count: 3}}\n")
    return path


def test_builtin_map_by_name() -> None:
    omap = load_scenario_map(scenario())
    assert omap.name == "open-6x6"
    assert omap.extent == (-3.0, 3.0, -3.0, 3.0)


@pytest.mark.parametrize("map_ref", ["maps/tiny.yaml", "./maps/tiny.yaml", "../shared/maps/tiny.yaml"])
def test_relative_map_path_is_taken_from_the_scenario_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, map_ref: str
) -> None:
    scen_dir = tmp_path / "runs"
    write_tiny_map(scen_dir / "maps")
    write_tiny_map(tmp_path / "shared" / "maps")
    path = write_scenario(scen_dir, map_ref)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    sc = load_scenario(str(path))
    omap = load_scenario_map(sc)
    assert omap.name == "tiny"
    assert omap.shape == (20, 30)
    assert omap.resolution == 0.1
    assert Path(omap.source).resolve() == (scen_dir / map_ref).resolve()


def test_bare_yaml_file_name_is_taken_from_the_scenario_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_tiny_map(tmp_path / "scen")
    path = write_scenario(tmp_path / "scen", "tiny.yaml")
    monkeypatch.chdir(tmp_path)
    omap = load_scenario_map(load_scenario(path))
    assert Path(omap.source).resolve() == (tmp_path / "scen" / "tiny.yaml").resolve()


def test_relative_map_path_survives_overrides(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_tiny_map(tmp_path / "scen" / "maps")
    path = write_scenario(tmp_path / "scen", "maps/tiny.yaml")
    monkeypatch.chdir(tmp_path)
    sc = load_scenario(path, overrides={"routers.count": 5}).with_overrides({"radio.r_c": 1.5})
    assert load_scenario_map(sc).shape == (20, 30)


def test_absolute_map_path_is_used_as_is(tmp_path: Path) -> None:
    map_path = write_tiny_map(tmp_path / "maps")
    path = write_scenario(tmp_path / "scen", str(map_path))
    omap = load_scenario_map(load_scenario(path))
    assert Path(omap.source) == map_path


def test_scenario_without_folder_takes_relative_paths_from_the_working_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_tiny_map(tmp_path / "maps")
    monkeypatch.chdir(tmp_path)
    sc = scenario(map="maps/tiny.yaml", base_stations=[{"x": 0.75, "y": 1.0}])
    assert sc.base_dir is None
    assert load_scenario_map(sc).shape == (20, 30)


def test_missing_map_file_is_a_map_error_on_the_map_field(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = write_scenario(tmp_path / "scen", "maps/nothing.yaml")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(MapError) as excinfo:
        load_scenario_map(load_scenario(path))
    exc = one_line_error(excinfo, "map")
    assert "not found" in exc.message
    assert str(tmp_path / "scen" / "maps" / "nothing.yaml") in exc.message


def test_unknown_map_name_is_a_map_error_on_the_map_field() -> None:
    with pytest.raises(MapError) as excinfo:
        load_scenario_map(scenario(map="no-such-map"))
    assert "unknown map 'no-such-map'" in one_line_error(excinfo, "map").message


def test_bad_map_value_keeps_its_map_subfield(tmp_path: Path) -> None:
    write_tiny_map(tmp_path / "scen" / "maps", resolution="-0.1")
    path = write_scenario(tmp_path / "scen", "maps/tiny.yaml")
    with pytest.raises(MapError) as excinfo:
        load_scenario_map(load_scenario(path))
    one_line_error(excinfo, "map.resolution")


def test_missing_map_image_keeps_the_map_image_field(tmp_path: Path) -> None:
    write_tiny_map(tmp_path / "scen" / "maps")
    (tmp_path / "scen" / "maps" / "tiny.pgm").unlink()
    path = write_scenario(tmp_path / "scen", "maps/tiny.yaml")
    with pytest.raises(MapError) as excinfo:
        load_scenario_map(load_scenario(path))
    one_line_error(excinfo, "map.image")


def test_map_errors_from_elsewhere_are_put_on_the_map_field(monkeypatch: pytest.MonkeyPatch) -> None:
    def fail(ref: str) -> None:
        raise MapError("seeds[0]", "something about the map")

    monkeypatch.setattr("amronet.sim.assemble.resolve_map", fail)
    with pytest.raises(MapError) as excinfo:
        load_scenario_map(scenario())
    assert one_line_error(excinfo, "map").message == "something about the map"


def test_bare_upper_case_yaml_name_is_taken_from_the_scenario_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    write_tiny_map(tmp_path / "scen")
    (tmp_path / "scen" / "tiny.yaml").rename(tmp_path / "scen" / "tiny.YAML")
    path = write_scenario(tmp_path / "scen", "tiny.YAML")
    monkeypatch.chdir(tmp_path)
    assert load_scenario_map(load_scenario(path)).shape == (20, 30)


# --- build_world ------------------------------------------------------------------------------------------


def cell_xy(omap, row: int, col: int) -> dict[str, float]:
    x, y = omap.cell_centres(np.array(row), np.array(col))
    return {"x": float(x), "y": float(y)}


def test_world_of_a_file_map_is_the_side_of_the_wall_the_base_is_on(tmp_path: Path) -> None:
    write_tiny_map(tmp_path / "scen" / "maps")
    world = build_world(load_scenario(write_scenario(tmp_path / "scen", "maps/tiny.yaml", x=0.75, y=1.0)))
    assert isinstance(world, World)
    assert world.reachable.shape == (20, 30)
    assert world.reachable.sum() == 18 * 14
    assert world.reachable[1:19, 1:15].all()
    assert not world.reachable[:, 15:].any()
    np.testing.assert_array_equal(world.bases_xy, [[0.75, 1.0]])


def test_world_loads_the_scenario_map_unless_one_is_given() -> None:
    sc = scenario()
    world = build_world(sc)
    assert world.omap.name == "open-6x6"
    assert world.reachable.sum() == world.omap.free.sum()  # the open arena is one room
    given_map = box_map(rows=40, cols=40)
    world = build_world(sc.with_overrides({"base_stations.0.x": 1.0, "base_stations.0.y": 1.0}), given_map)
    assert world.omap is given_map
    assert world.reachable.shape == (40, 40)


def test_reachable_is_the_free_part_4_connected_to_the_bases() -> None:
    omap = box_map(rows=40, cols=60, walls=[(slice(None), 30)])
    left, right = cell_xy(omap, 20, 10), cell_xy(omap, 20, 45)
    world = build_world(scenario(base_stations=[left]), omap)
    assert world.reachable.sum() == 38 * 29
    assert world.reachable[1:39, 1:30].all()
    assert not world.reachable[:, 30:].any()
    assert not (world.reachable & ~omap.free).any()
    world = build_world(scenario(base_stations=[left, right]), omap)
    assert world.reachable.sum() == 38 * 29 + 38 * 28
    np.testing.assert_array_equal(world.bases_xy, [[left["x"], left["y"]], [right["x"], right["y"]]])


def test_a_one_cell_door_joins_the_rooms() -> None:
    omap = box_map(rows=40, cols=60, walls=[(slice(0, 20), 30), (slice(21, None), 30)])
    world = build_world(scenario(base_stations=[cell_xy(omap, 20, 10)]), omap)
    np.testing.assert_array_equal(world.reachable, omap.free)


def test_diagonal_wall_does_not_leak_between_corners() -> None:
    omap = diagonal_wall_map(n=60)
    world = build_world(scenario(base_stations=[cell_xy(omap, 10, 45)]), omap)
    rows, cols = np.nonzero(world.reachable)
    assert len(rows) == 57 * 58 // 2
    assert (rows < cols).all()


def test_unknown_cells_bound_the_reachable_space() -> None:
    omap = box_map(rows=40, cols=60)
    cells = omap.cells.copy()
    cells[:, 30] = UNKNOWN
    omap = type(omap)(name="box", resolution=omap.resolution, origin=omap.origin, cells=cells)
    world = build_world(scenario(base_stations=[cell_xy(omap, 20, 10)]), omap)
    assert world.reachable.sum() == 38 * 29


@pytest.mark.parametrize(("x", "y"), [(3.5, 0.0), (0.0, -3.01), (-10.0, 10.0)])
def test_base_station_off_the_map_is_refused(x: float, y: float) -> None:
    sc = scenario(base_stations=[{"x": 0.0, "y": 0.0}, {"x": x, "y": y}])
    with pytest.raises(ScenarioError) as excinfo:
        build_world(sc)
    exc = one_line_error(excinfo, "base_stations[1]")
    assert "outside the map" in exc.message
    assert f"({x:g}, {y:g})" in exc.message


def test_base_station_in_an_obstacle_is_refused() -> None:
    sc = scenario(map="obstacles-6x6", base_stations=[{"x": -1.5, "y": -0.8}, {"x": -2.0, "y": 2.0}])
    with pytest.raises(ScenarioError) as excinfo:
        build_world(sc)
    assert "inside an obstacle" in one_line_error(excinfo, "base_stations[1]").message


def test_base_station_in_a_hand_made_wall_or_unknown_cell_is_refused() -> None:
    omap = box_map(rows=40, cols=60, walls=[(slice(None), 30)])
    with pytest.raises(ScenarioError) as excinfo:
        build_world(scenario(base_stations=[cell_xy(omap, 20, 30)]), omap)
    one_line_error(excinfo, "base_stations[0]")
    cells = omap.cells.copy()
    cells[20, 10] = UNKNOWN
    omap = type(omap)(name="box", resolution=omap.resolution, origin=omap.origin, cells=cells)
    with pytest.raises(ScenarioError, match=r"inside an obstacle or unknown space") as excinfo:
        build_world(scenario(base_stations=[cell_xy(omap, 20, 10)]), omap)
    one_line_error(excinfo, "base_stations[0]")


def test_base_station_too_close_to_a_wall_for_its_body_is_refused() -> None:
    sc = scenario(map="obstacles-6x6", base_stations=[{"x": -2.0, "y": -2.0}])  # 0.09 m from a wall
    with pytest.raises(ScenarioError) as excinfo:
        build_world(sc)
    exc = one_line_error(excinfo, "base_stations[0]")
    assert "too close" in exc.message
    assert f"{AMIGOBOT.radius:g}" in exc.message


def test_a_small_base_body_fits_where_the_amigobot_does_not() -> None:
    sc = scenario(map="obstacles-6x6", base_stations=[{"x": -2.0, "y": -2.0, "robot": TINY_BASE}])
    world = build_world(sc)
    assert world.reachable[world.omap.world_to_cell(np.array([-2.0, -2.0]))]


def test_base_station_with_an_unknown_robot_is_refused() -> None:
    with pytest.raises(ScenarioError) as excinfo:
        build_world(scenario(base_stations=[{"x": 0.0, "y": 0.0, "robot": "r2d2"}]))
    one_line_error(excinfo, "base_stations[0].robot")


# --- build_swarm ------------------------------------------------------------------------------------------

TWO_BASES = [{"x": -1.5, "y": -0.8, "region": [1.8, 1.8]}, {"x": 0.5, "y": -1.5, "region": [1.8, 1.4]}]


@functools.cache
def obstacles_world() -> World:
    return build_world(scenario(map="obstacles-6x6", base_stations=TWO_BASES))


def obstacles_scenario(routers: int, per_base: int = 0) -> Scenario:
    return scenario(map="obstacles-6x6", base_stations=TWO_BASES, routers={"count": routers},
                    agents={"per_base": per_base})


def assert_no_body_overlap(swarm) -> None:
    gap = np.linalg.norm(swarm.xy[:, None, :] - swarm.xy[None, :, :], axis=2)
    np.fill_diagonal(gap, np.inf)
    reach = swarm.radius[:, None] + swarm.radius[None, :]
    i, j = np.nonzero(gap < reach - 1e-12)
    assert len(i) == 0, f"robots {list(zip(i.tolist(), j.tolist(), strict=True))[:5]} overlap"


def assert_clear_of_obstacles(swarm, world: World) -> None:
    omap = world.omap
    rows, cols = omap.world_to_cell(swarm.xy)
    assert omap.inside(swarm.xy).all()
    assert (clearance(omap)[rows, cols] >= swarm.radius).all()
    # geometrically: a body reaches into no blocked cell by more than one cell (clearance is cell-based)
    br, bc = np.nonzero(omap.blocked)
    lo = omap.cell_centres(br, bc) - omap.resolution / 2
    hi = lo + omap.resolution
    nearest = np.clip(swarm.xy[:, None, :], lo[None], hi[None])
    dist = np.linalg.norm(swarm.xy[:, None, :] - nearest, axis=2).min(axis=1)
    assert (dist >= swarm.radius - omap.resolution).all()


def router_blocks(n_bases: int, count: int) -> list[slice]:
    """Ids of every base station's routers: round-robin counts, one block per base after the base nodes."""
    counts = [len(range(i, count, n_bases)) for i in range(n_bases)]
    starts = np.concatenate([[n_bases], n_bases + np.cumsum(counts)])
    return [slice(int(a), int(b)) for a, b in itertools.pairwise(starts)]


def assert_near_base(xy: np.ndarray, base: np.ndarray, region: tuple[float, float], r_start: float) -> None:
    assert (np.linalg.norm(xy - base, axis=1) <= r_start).all()
    assert (np.abs(xy - base) <= np.asarray(region) / 2).all()


def test_swarm_has_the_right_robots_of_each_kind() -> None:
    sc = obstacles_scenario(routers=7, per_base=2)
    swarm = build_swarm(sc, obstacles_world(), np.random.default_rng(0), R_START)
    assert len(swarm) == 2 + 7 + 4
    np.testing.assert_array_equal(swarm.role, [Role.BASE] * 2 + [Role.ROUTER] * 7 + [Role.AGENT] * 4)
    np.testing.assert_array_equal(swarm.state, [State.BASE] * 2 + [State.EXPLORE] * 7 + [State.AGENT] * 4)
    np.testing.assert_array_equal(swarm.status, [0, 1] + [-1] * 7 + [0, 0, 1, 1])
    np.testing.assert_array_equal(swarm.xy[:2], obstacles_world().bases_xy)
    np.testing.assert_array_equal(swarm.radius, [AMIGOBOT.radius] * 2 + [BEBOT.radius] * 7 + [PIONEER.radius] * 4)
    assert set(swarm.models) == {AMIGOBOT, BEBOT, PIONEER}
    assert not swarm.distance.any()
    assert (np.abs(swarm.heading) <= np.pi).all()
    assert len(np.unique(swarm.heading)) == len(swarm)


def test_routers_start_round_robin_near_their_base() -> None:
    sc = obstacles_scenario(routers=7)
    world = obstacles_world()
    swarm = build_swarm(sc, world, np.random.default_rng(1), R_START)
    blocks = router_blocks(2, 7)
    assert [b.stop - b.start for b in blocks] == [4, 3]
    for i, block in enumerate(blocks):
        assert_near_base(swarm.xy[block], world.bases_xy[i], sc.base_stations[i].region, R_START)


def test_routers_respect_a_start_range_smaller_than_the_region() -> None:
    sc = scenario(base_stations=[{"x": 0.0, "y": 0.0, "region": [2.0, 2.0]}], routers={"count": 30})
    swarm = build_swarm(sc, build_world(sc), np.random.default_rng(2), 0.4)
    assert (np.linalg.norm(swarm.xy[1:], axis=1) <= 0.4).all()


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(min_value=0, max_value=2**32 - 1),
    routers=st.integers(min_value=0, max_value=24),
    per_base=st.integers(min_value=0, max_value=2),
)
def test_start_positions_are_valid_for_any_seed(seed: int, routers: int, per_base: int) -> None:
    sc = obstacles_scenario(routers=routers, per_base=per_base)
    world = obstacles_world()
    swarm = build_swarm(sc, world, np.random.default_rng(seed), R_START)
    assert len(swarm) == 2 + routers + 2 * per_base
    assert (swarm.role == Role.ROUTER).sum() == routers
    assert (swarm.role == Role.AGENT).sum() == 2 * per_base
    assert_no_body_overlap(swarm)
    assert_clear_of_obstacles(swarm, world)
    rows, cols = world.omap.world_to_cell(swarm.xy)
    assert world.reachable[rows, cols].all()
    for i, block in enumerate(router_blocks(2, routers)):
        assert_near_base(swarm.xy[block], world.bases_xy[i], sc.base_stations[i].region, R_START)
    agents = np.flatnonzero(swarm.role == Role.AGENT)
    for i in range(2):
        mine = agents[swarm.status[agents] == i]
        assert len(mine) == per_base
        assert_near_base(swarm.xy[mine], world.bases_xy[i], sc.base_stations[i].region, R_START)


def test_same_seed_gives_identical_arrays() -> None:
    sc = obstacles_scenario(routers=12, per_base=1)
    a = build_swarm(sc, obstacles_world(), np.random.default_rng(5), R_START)
    b = build_swarm(sc, obstacles_world(), np.random.default_rng(5), R_START)
    assert a.models == b.models
    for f in ROW_FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


def test_different_seeds_give_different_positions() -> None:
    sc = obstacles_scenario(routers=12, per_base=1)
    a = build_swarm(sc, obstacles_world(), np.random.default_rng(5), R_START)
    b = build_swarm(sc, obstacles_world(), np.random.default_rng(6), R_START)
    np.testing.assert_array_equal(a.xy[:2], b.xy[:2])  # the base nodes do not move
    assert not np.any(np.all(a.xy[2:] == b.xy[2:], axis=1))
    assert not np.array_equal(a.heading, b.heading)


def test_no_routers_gives_only_the_base_nodes() -> None:
    sc = obstacles_scenario(routers=0)
    swarm = build_swarm(sc, obstacles_world(), np.random.default_rng(0), R_START)
    np.testing.assert_array_equal(swarm.role, [Role.BASE, Role.BASE])
    assert swarm.models == (AMIGOBOT,)


def test_custom_router_robot_is_used() -> None:
    robot = {"radius": 0.03, "max_speed": 0.15, "sensor_beams": 6, "sensor_range": 0.2}
    sc = scenario(routers={"count": 5, "robot": robot})
    swarm = build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    routers = swarm.role == Role.ROUTER
    np.testing.assert_array_equal(swarm.radius[routers], np.full(5, 0.03))
    np.testing.assert_array_equal(swarm.max_speed[routers], np.full(5, 0.15))
    assert swarm.models[swarm.model[1]] == RobotModel("custom", 0.03, 0.15, 6, 0.2)


def test_unknown_router_or_agent_robot_is_refused() -> None:
    sc = scenario(routers={"count": 3, "robot": "roomba"})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    one_line_error(excinfo, "routers.robot")
    sc = scenario(agents={"per_base": 1, "robot": "roomba"})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    one_line_error(excinfo, "agents.robot")


def test_region_too_small_for_its_routers_is_refused() -> None:
    sc = scenario(base_stations=[{"x": 0.0, "y": 0.0, "region": [0.4, 0.4]}], routers={"count": 40})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    exc = one_line_error(excinfo, "base_stations[0].region")
    assert "of 40 robots" in exc.message


def test_the_region_named_is_the_one_too_small() -> None:
    bases = [{"x": -1.0, "y": 0.0}, {"x": 1.0, "y": 0.0, "region": [0.4, 0.4]}]
    sc = scenario(base_stations=bases, routers={"count": 60})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    one_line_error(excinfo, "base_stations[1].region")


def test_region_too_small_for_its_agents_is_refused() -> None:
    sc = scenario(base_stations=[{"x": 0.0, "y": 0.0, "region": [0.8, 0.8]}], routers={"count": 0},
                  agents={"per_base": 6})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), R_START)
    one_line_error(excinfo, "base_stations[0].region")


def test_start_range_too_small_for_the_routers_is_refused() -> None:
    sc = scenario(routers={"count": 20})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc), np.random.default_rng(0), 0.25)
    one_line_error(excinfo, "base_stations[0].region")


# --- build_swarm, routers scattered uniformly -------------------------------------------------------------


def test_uniform_routers_stay_in_the_reachable_space() -> None:
    omap = box_map(rows=40, cols=60, walls=[(slice(None), 30)])
    sc = scenario(base_stations=[cell_xy(omap, 20, 10)], routers={"count": 40, "start": "uniform"})
    world = build_world(sc, omap)
    swarm = build_swarm(sc, world, np.random.default_rng(3), R_START)
    routers = swarm.role == Role.ROUTER
    assert routers.sum() == 40
    np.testing.assert_array_equal(swarm.state[routers], np.full(40, State.EXPLORE))
    np.testing.assert_array_equal(swarm.status[routers], np.full(40, -1))
    rows, cols = omap.world_to_cell(swarm.xy)
    assert world.reachable[rows, cols].all()
    assert (cols < 30).all()
    assert_no_body_overlap(swarm)
    assert_clear_of_obstacles(swarm, world)


def test_uniform_routers_spread_beyond_the_start_region() -> None:
    sc = scenario(routers={"count": 200, "start": "uniform"})
    swarm = build_swarm(sc, build_world(sc), np.random.default_rng(4), R_START)
    dist = np.linalg.norm(swarm.xy[swarm.role == Role.ROUTER], axis=1)
    assert dist.max() > 2.0
    assert_no_body_overlap(swarm)


def test_uniform_routers_are_deterministic_per_seed() -> None:
    sc = scenario(routers={"count": 50, "start": "uniform"})
    world = build_world(sc)
    a = build_swarm(sc, world, np.random.default_rng(9), R_START)
    b = build_swarm(sc, world, np.random.default_rng(9), R_START)
    c = build_swarm(sc, world, np.random.default_rng(10), R_START)
    np.testing.assert_array_equal(a.xy, b.xy)
    assert not np.array_equal(a.xy, c.xy)


def test_too_many_uniform_routers_are_refused() -> None:
    omap = box_map(rows=12, cols=12)
    sc = scenario(base_stations=[cell_xy(omap, 6, 6)], routers={"count": 500, "start": "uniform"})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc, omap), np.random.default_rng(0), R_START)
    assert "of 500 routers" in one_line_error(excinfo, "routers.count").message


def test_uniform_routers_need_a_cell_wide_enough() -> None:
    omap = box_map(rows=3, cols=3)  # one free cell, 0.025 m from the walls: too narrow for a Bebot
    sc = scenario(base_stations=[{**cell_xy(omap, 1, 1), "robot": TINY_BASE}], routers={"count": 1,
                                                                                         "start": "uniform"})
    with pytest.raises(ScenarioError) as excinfo:
        build_swarm(sc, build_world(sc, omap), np.random.default_rng(0), R_START)
    one_line_error(excinfo, "routers.start")


@pytest.mark.parametrize("seed", range(5))
def test_agents_do_not_overlap_uniformly_scattered_routers(seed: int) -> None:
    # 60 routers over 36 m² leave room for the agents' region; before the fix 300 gave 3 to 13 overlapping pairs
    sc = scenario(routers={"count": 60, "start": "uniform"}, agents={"per_base": 3})
    swarm = build_swarm(sc, build_world(sc), np.random.default_rng(seed), R_START)
    assert_no_body_overlap(swarm)



@pytest.mark.parametrize(("second", "gap"), [((0.0, 0.0), "0 m"), ((0.31, 0.0), "0.31 m")])
def test_base_stations_whose_bodies_overlap_are_refused_naming_both(second: tuple[float, float], gap: str) -> None:
    # two AmigoBot reference nodes (radius 0.165 m) need 0.33 m between their centres
    sc = load_scenario({"map": "open-6x6", "base_stations": [{"x": 0.0, "y": 0.0}, {"x": second[0], "y": second[1]}]})
    with pytest.raises(ScenarioError) as excinfo:
        build_world(sc)
    err = one_line_error(excinfo, "base_stations[1]")
    assert "base_stations[0]" in err.message and gap in err.message and "0.33 m" in err.message


def test_base_stations_just_far_enough_apart_are_accepted() -> None:
    sc = load_scenario({"map": "open-6x6", "base_stations": [{"x": 0.0, "y": 0.0}, {"x": 0.34, "y": 0.0}]})
    assert build_world(sc).bases_xy.shape == (2, 2)
