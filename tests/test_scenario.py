import math

import pytest

from amronet.errors import ScenarioError
from amronet.scenario import apply_overrides, list_presets, load_scenario, parse_override

BASE = {
    "map": "open-6x6",
    "base_stations": [{"x": 0.0, "y": 0.0}],
}


def err(data, **kw) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        load_scenario(data, **kw)
    text = str(info.value)
    assert "\n" not in text
    return info.value


def test_defaults_fill_in():
    sc = load_scenario(BASE)
    assert sc.radio.r_c == 1.0 and sc.routers.count == 30 and sc.algorithm.name == "self-spreading"
    assert sc.algorithm_params().triangular == "local"


def test_presets_load():
    presets = list_presets()
    assert "self-spreading-6x6" in presets
    for name in presets:
        assert load_scenario(name).name == name


@pytest.mark.parametrize(
    ("data", "field", "words"),
    [
        ({**BASE, "colour": "red"}, "colour", "unknown key"),
        ({**BASE, "radio": {"r_c": -1}}, "radio.r_c", "greater than 0"),
        ({**BASE, "radio": {"r_c": math.nan}}, "radio.r_c", "finite"),
        ({**BASE, "radio": {"r_c": "far"}}, "radio.r_c", "number"),
        ({**BASE, "routers": {"count": 2.5}}, "routers.count", "integer"),
        ({**BASE, "routers": {"count": True}}, "routers.count", "integer"),
        ({**BASE, "routers": {"robot": {"radius": 0.1, "max_speed": -1, "sensor_beams": 8, "sensor_range": 1}}},
         "routers.robot", ""),
        ({**BASE, "base_stations": []}, "base_stations", "at least 1"),
        ({**BASE, "base_stations": [{"x": 0, "y": 0, "zz": 1}]}, "base_stations[0].zz", "allowed keys here: x, y"),
        ({**BASE, "algorithm": {"name": "magic"}}, "algorithm.name", "self-spreading"),
        ({**BASE, "algorithm": {"params": {"triangular": "maybe"}}}, "algorithm.params.triangular", "local"),
        ({**BASE, "algorithm": {"params": {"bogus": 1}}}, "algorithm.params.bogus", "loss_margin"),
        ({**BASE, "sim": {"dt": 0}}, "sim.dt", "greater than 0"),
        ({"base_stations": [{"x": 0, "y": 0}]}, "map", "missing"),
        ([1, 2], "scenario", "mapping"),
    ],
)
def test_bad_fields_name_the_field(data, field, words):
    e = err(data)
    assert str(e).startswith(field), str(e)
    assert words in str(e)


def test_yaml_file_and_syntax_error(tmp_path):
    good = tmp_path / "s.yaml"
    good.write_text("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\n")
    assert load_scenario(good).base_dir == str(tmp_path)
    bad = tmp_path / "bad.yaml"
    bad.write_text("map: [open\n")
    assert "not valid YAML" in str(err(bad))
    assert "no file" in str(err(tmp_path / "missing.yaml"))


def test_overrides():
    sc = load_scenario(BASE, overrides={"radio.r_c": 1.5, "routers.count": 60, "base_stations.0.x": 0.5})
    assert sc.radio.r_c == 1.5 and sc.routers.count == 60 and sc.base_stations[0].x == 0.5
    assert sc.with_overrides({"sim.dt": 0.05}).sim.dt == 0.05
    assert parse_override("radio.r_c=1.5") == ("radio.r_c", 1.5)
    assert parse_override("sim.stop_when_settled=false") == ("sim.stop_when_settled", False)
    with pytest.raises(ScenarioError):
        parse_override("nothing")
    with pytest.raises(ScenarioError, match="no list item 3"):
        apply_overrides({"base_stations": [{}]}, {"base_stations.3.x": 1})
    assert str(err(BASE, overrides={"radio.rc": 2})).startswith("radio.rc: unknown key")


@pytest.mark.parametrize(("key", "value", "field"), [
    ("radio.r_c", True, "radio.r_c"),
    ("base_stations.0.x", False, "base_stations[0].x"),
    ("sim.dt", True, "sim.dt"),
    ("algorithm.params.loss_margin", True, "algorithm.params.loss_margin"),
    ("radio.r_c", "1.5", "radio.r_c"),
])
def test_booleans_and_strings_are_not_numbers(key, value, field):
    with pytest.raises(ScenarioError) as excinfo:
        # the algorithm's own parameters are validated when a run starts
        load_scenario("self-spreading-6x6", overrides={key: value}).algorithm_params()
    assert excinfo.value.field == field


@pytest.mark.parametrize(("robot", "field"), [
    ({"radius": 0.05, "max_speed": 0.1, "sensor_beams": 0, "sensor_range": 0.2}, "routers.robot.sensor_beams"),
    ({"radius": 0.05, "max_speed": float("nan"), "sensor_beams": 8, "sensor_range": 0.2}, "routers.robot.max_speed"),
    ({"radius": 0.05, "max_speed": 0.1, "sensor_beams": 8, "sensor_range": 0.2, "colour": "red"},
     "routers.robot.colour"),
    (5, "routers.robot"),
])
def test_a_robot_given_field_by_field_names_the_real_field(robot, field):
    with pytest.raises(ScenarioError) as excinfo:
        load_scenario({"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"robot": robot}})
    assert excinfo.value.field == field
    if field.endswith("colour"):
        assert "radius, max_speed, sensor_beams, sensor_range" in excinfo.value.message


def test_switching_the_algorithm_drops_the_base_s_parameters_for_every_caller():
    sc = load_scenario("self-spreading-6x6", overrides={"algorithm.name": "dssa"})
    assert sc.algorithm.name == "dssa" and sc.algorithm.params == {}
    sc.algorithm_params()  # DSSA's defaults, not self-spreading's parameters
    sc = load_scenario("self-spreading-6x6", overrides={"algorithm.name": "dssa", "algorithm.params.field_area": 30.0})
    assert sc.algorithm_params().field_area == 30.0
    same = load_scenario("self-spreading-6x6", overrides={"algorithm.name": "self-spreading"})
    assert same.algorithm.params == load_scenario("self-spreading-6x6").algorithm.params
    switched = load_scenario("self-spreading-6x6").with_overrides({"algorithm.name": "potential-field"})
    assert switched.algorithm.params == {}


# -- issue #45 (5b, 5f): numbers as YAML 1.2 reads them, a key given twice refused ----------------------------------

def test_set_reads_exponents_without_a_dot():
    assert parse_override("sim.dt=1e-3") == ("sim.dt", 1e-3)
    assert parse_override("radio.r_c=1e300") == ("radio.r_c", 1e300)
    assert parse_override("routers.count=010") == ("routers.count", 10)
    sc = load_scenario("self-spreading-6x6", dict([parse_override("sim.dt=5e-2"), parse_override("radio.r_c=15E-1")]))
    assert sc.sim.dt == 0.05 and sc.radio.r_c == 1.5


def test_set_refuses_a_mapping_with_a_key_twice():
    with pytest.raises(ScenarioError) as info:
        parse_override("radio={r_c: 1, r_c: 2}")
    assert str(info.value) == ("radio: key 'r_c' appears twice in value '{r_c: 1, r_c: 2}' (line 1, columns 2 and "
                               "10); keep one")


def test_a_scenario_file_reads_exponents_and_refuses_a_key_twice(tmp_path):
    good = tmp_path / "s.yaml"
    good.write_text("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: 15e-1}\nsim: {dt: 5E-2}\n")
    sc = load_scenario(good)
    assert sc.radio.r_c == 1.5 and sc.sim.dt == 0.05
    bad = tmp_path / "scenario.yaml"
    bad.write_text("map: open-6x6\nradio: {r_c: 1.0}\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: 2.0}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(bad)
    assert str(info.value) == (f"scenario: key 'radio' appears twice in {str(bad)!r} (lines 2 and 4); keep one")


def test_a_scenario_file_with_inf_is_still_refused_where_a_finite_value_is_needed(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: 1e999}\n")
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value).startswith("radio.r_c: input should be a finite number")


# -- defaults that fit the algorithm: agent-assisted deployment, start regions -----------------------------------
AGENTS = {"map": "office-32x32", "algorithm": {"name": "agent-assisted"}, "base_stations": [{"x": 1.0, "y": 1.0}],
          "agents": {"per_base": 3}}
"""An agent-assisted scenario as a user writes it: a map, the algorithm, one base station and its agents."""


def test_agent_assisted_scenarios_default_to_no_free_routers_and_the_agents_range():
    """Agents release the routers: none start free unless given, and ``r_c`` is the paper's agent-assisted 6 m."""
    sc = load_scenario(AGENTS)
    assert sc.routers.count == 0 and sc.radio.r_c == 6.0 and sc.agents.per_base == 3
    assert load_scenario({**AGENTS, "agents": {}}).agents.per_base == 3
    given = load_scenario({**AGENTS, "routers": {"count": 5}, "radio": {"r_c": 3.0}, "agents": {"per_base": 1}})
    assert given.routers.count == 5 and given.radio.r_c == 3.0 and given.agents.per_base == 1
    assert load_scenario({**AGENTS, "radio": {"threshold_dbm": -70.0}}).radio.r_c != 6.0  # the threshold's range
    other = load_scenario({**AGENTS, "algorithm": {"name": "self-spreading"}})
    assert other.routers.count == 30 and other.radio.r_c == 1.0
    # the defaults are written out, so the scenario means the same wherever it is loaded again
    again = load_scenario(sc.to_dict())
    assert again.to_dict() == sc.to_dict()


def test_a_default_start_region_holds_its_robots_and_stays_1_m_where_that_does():
    from amronet.scenario.defaults import fitted_side

    assert load_scenario(AGENTS).base_stations[0].region == (1.0, 1.0)
    assert load_scenario(BASE).base_stations[0].region == (1.0, 1.0)  # 30 routers: the paper's 1 m x 1 m
    twelve = load_scenario({**AGENTS, "agents": {"per_base": 12}}).base_stations[0].region
    assert twelve[0] == twelve[1] > 1.0
    given = load_scenario({**AGENTS, "base_stations": [{"x": 1.0, "y": 1.0, "region": [0.5, 0.5]}]})
    assert given.base_stations[0].region == (0.5, 0.5)
    assert fitted_side(12, 0.22, 0.165) == twelve[0] and fitted_side(10**7, 0.22, 0.165) > 1000.0


@pytest.mark.parametrize("agents", [3, 9, 12, 20])
def test_agents_start_in_a_default_region_in_open_floor(agents):
    """Twelve agents did not fit the 1 m x 1 m region that was the default for every scenario."""
    import numpy as np

    from amronet.sim.assemble import build_swarm, build_world

    sc = load_scenario({**AGENTS, "map": "open-32x32", "base_stations": [{"x": 16.0, "y": 16.0}],
                        "agents": {"per_base": agents}})
    for seed in (1, 2):
        swarm = build_swarm(sc, build_world(sc), np.random.default_rng(seed), r_start=5.7)
        assert len(swarm) == 1 + agents


def test_a_minimal_agent_assisted_scenario_file_runs(tmp_path):
    """The file a user writes first: map, algorithm, one base station, agents; it ran only with routers.count: 0."""
    import amronet

    path = tmp_path / "agents.yaml"
    path.write_text("map: office-32x32\nalgorithm: {name: agent-assisted}\nbase_stations:\n  - {x: 1.0, y: 1.0}\n"
                    "agents: {per_base: 3}\nsim: {time_limit: 120}\n")
    result = amronet.run(amronet.load_scenario(path), seed=1)
    s = result.summary
    assert s["routers_total"] > 0 and s["agents_connected_min"] == 1.0 and s["coverage"] > 0.2


def test_an_override_computes_the_defaults_that_follow_the_algorithm_and_the_robots_again():
    """A sweep's point (or ``with_overrides``) with another algorithm or more agents gets the defaults that fit it;
    fields the scenario gives stay as given."""
    agents = load_scenario(AGENTS)
    more = agents.with_overrides({"agents.per_base": 12})
    assert more.base_stations[0].region == load_scenario({**AGENTS, "agents": {"per_base": 12}}).base_stations[0].region
    assert more.base_stations[0].region != (1.0, 1.0) and more.routers.count == 0
    back = agents.with_overrides({"algorithm.name": "self-spreading"})
    assert back.routers.count == 30 and back.radio.r_c == 1.0
    spreading = load_scenario({**BASE, "radio": {"r_c": 4.0}})
    switched = spreading.with_overrides({"algorithm.name": "agent-assisted"})
    assert switched.routers.count == 0 and switched.agents.per_base == 3 and switched.radio.r_c == 4.0
    assert load_scenario(agents, {"agents.per_base": 12}).to_dict() == more.to_dict()
    given = load_scenario({**AGENTS, "routers": {"count": 4}, "radio": {"r_c": 3.0},
                           "base_stations": [{"x": 1.0, "y": 1.0, "region": [1.0, 1.0]}]})
    kept = given.with_overrides({"agents.per_base": 12, "algorithm.name": "self-spreading"})
    assert kept.routers.count == 4 and kept.radio.r_c == 3.0 and kept.base_stations[0].region == (1.0, 1.0)


@pytest.mark.parametrize(("section", "value", "message"), [
    ("algorithm", "self-spreading", "algorithm: must be a mapping of its fields (got 'self-spreading'); its keys: "
                                    "name, params"),
    ("radio", 4, "radio: must be a mapping of its fields (got 4); its keys: model, r_c, "),
    ("base_stations", [1], "base_stations[0]: must be a mapping of its fields (got 1); its keys: x, y, region, "),
])
def test_a_section_given_a_plain_value_names_its_keys_not_a_class(section, value, message):
    text = str(err({**BASE, section: value}))
    assert text.startswith(message), text
    assert "Spec" not in text


@pytest.mark.parametrize("text", ["", "# only a comment\n"])
def test_an_empty_scenario_file_says_so(tmp_path, text):
    path = tmp_path / "empty.yaml"
    path.write_text(text)
    assert str(err(str(path))) == f"scenario: {str(path)!r} is empty; give at least map and base_stations"
