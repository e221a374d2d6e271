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
