"""Words YAML 1.1 turned into booleans (``off``, ``yes``...), numbers and deep nesting, in every place users write them.

The one YAML reader (:mod:`amronet.yaml_loading`) reads YAML 1.2's core schema: only ``true`` / ``false`` are
booleans. A field whose values are words takes the words as written (``sim.coverage_target: off``), a boolean field
takes ``true`` / ``false`` and the words yes / no, on / off, y / n, and a text field refuses a boolean or a number.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from amronet.algorithms import ALGORITHMS
from amronet.algorithms.agent_assisted.drops import DROP_RULES
from amronet.cli import main
from amronet.engine.radio import MEDIA
from amronet.errors import MapError, ScenarioError
from amronet.scenario import load_scenario, parse_override
from amronet.sweeps import load_sweep
from amronet.world import load_map_yaml

WORDS = ["on", "off", "yes", "no", "y", "n", "On", "OFF", "Yes", "NO", "true", "false", "True", "FALSE", "null", "~",
         "none", "1e3", "010", "2024-05-01"]
"""Plain words a user may write unquoted; YAML 1.1 read the first ten and the last as booleans and a date."""

TRIANGULAR = {"off", "none", "global", "local"}
ENUM_FIELDS = [  # (dotted path, algorithm, the words the field takes: a value of its own)
    ("sim.coverage_target", "self-spreading", {"off"}),
    ("sim.coverage_method", "self-spreading", {"raster", "exact"}),
    ("routers.start", "self-spreading", {"base", "uniform"}),
    ("agents.when_empty", "agent-assisted", {"tether", "continue"}),
    ("radio.model", "self-spreading", set(MEDIA)),
    ("algorithm.name", "self-spreading", set(ALGORITHMS)),
    ("algorithm.params.triangular", "self-spreading", TRIANGULAR),
    ("algorithm.params.triangular", "agent-assisted", TRIANGULAR),
    ("algorithm.params.stop_rule", "self-spreading", {"distance", "link-quality"}),
    ("algorithm.params.triangle_rule", "self-spreading", {"geometric", "link-quality"}),
    ("algorithm.params.walk", "self-spreading", {"random", "straight", "growth", "guided"}),
    ("algorithm.params.repair", "agent-assisted", {"none", "relocate", "retrace"}),
    ("algorithm.params.drop_rule", "agent-assisted", set(DROP_RULES)),
]
TEXT_FIELDS = [  # any text when the scenario is read (a name is looked up when the run is set up)
    ("name", "self-spreading"), ("description", "self-spreading"), ("map", "self-spreading"),
    ("routers.robot", "self-spreading"), ("base_stations.0.robot", "self-spreading"),
    ("algorithm.params.explorer", "agent-assisted"),
]
BOOL_FIELDS = [
    ("radio.packet_loss", "self-spreading"), ("sim.stop_when_settled", "self-spreading"),
    ("sim.robot_collisions", "self-spreading"), ("algorithm.params.obstacle_forces", "dssa"),
    ("algorithm.params.obstacle_forces", "potential-field"),
]
TRUE_WORDS, FALSE_WORDS = {"on", "yes", "y", "true"}, {"off", "no", "n", "false"}


def _flow(parts: list[str], word: str) -> str:
    return word if not parts else "{" + parts[0] + ": " + _flow(parts[1:], word) + "}"


def _scenario(algorithm: str, dotted: str, word: str, how: str, tmp_path: Path):
    """The scenario with ``dotted`` set to the unquoted ``word``, written in a file or given as ``--set``."""
    if how == "set":
        key, value = parse_override(f"{dotted}={word}")
        return load_scenario({"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}],
                              "algorithm": {"name": algorithm}}, {key: value})
    lines = {"map": "open-6x6", "base_stations": "[{x: 0, y: 0}]", "algorithm": f"{{name: {algorithm}}}"}
    parts = dotted.split(".")
    if parts[0] == "algorithm" and parts[1] == "params":
        lines["algorithm"] = f"{{name: {algorithm}, params: {_flow(parts[2:], word)}}}"
    elif parts[0] == "algorithm":
        lines["algorithm"] = f"{{name: {word}}}"
    elif parts[0] == "base_stations":
        lines["base_stations"] = f"[{{x: 0, y: 0, robot: {word}}}]"
    else:
        lines[parts[0]] = _flow(parts[1:], word)
    path = tmp_path / "s.yaml"
    path.write_text("".join(f"{k}: {v}\n" for k, v in lines.items()))
    return load_scenario(path)


def _value(sc, dotted: str):
    if dotted.startswith("algorithm.params."):
        return getattr(sc.algorithm_params(), dotted.rsplit(".", 1)[1])
    node = sc
    for part in dotted.split("."):
        node = node[int(part)] if part.isdigit() else getattr(node, part)
    return node


def _field(dotted: str) -> str:
    return dotted.replace("base_stations.0", "base_stations[0]")


@pytest.mark.parametrize("how", ["file", "set"])
def test_coverage_target_off_as_the_readme_writes_it(how, tmp_path):
    assert _value(_scenario("self-spreading", "sim.coverage_target", "off", how, tmp_path),
                  "sim.coverage_target") == "off"


def test_coverage_target_off_on_the_command_line(tmp_path, capsys):
    out = tmp_path / "o"
    code = main(["run", "--preset", "self-spreading-6x6", "--out", str(out), "--set", "sim.coverage_target=off",
                 "--set", "sim.time_limit=2", "--no-snapshot", "-q"])
    assert code == 0, capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text())["sim_time_s"] == 2


@pytest.mark.parametrize("how", ["file", "set"])
@pytest.mark.parametrize("word", WORDS)
@pytest.mark.parametrize(("dotted", "algorithm", "values"), ENUM_FIELDS,
                         ids=[f"{d}-{a}" for d, a, _ in ENUM_FIELDS])
def test_a_field_of_words_takes_its_words_as_written(dotted, algorithm, values, word, how, tmp_path):
    if dotted == "algorithm.name" and how == "file":  # the file names the algorithm by that key
        algorithm = word
    null = dotted == "sim.coverage_target" and word in ("null", "~")
    if word in values or null:
        assert _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted) == (None if null else word)
    else:
        with pytest.raises(ScenarioError) as info:
            _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert info.value.field == dotted and "\n" not in str(info.value)


@pytest.mark.parametrize("how", ["file", "set"])
@pytest.mark.parametrize("word", WORDS)
@pytest.mark.parametrize(("dotted", "algorithm"), TEXT_FIELDS, ids=[d for d, _ in TEXT_FIELDS])
def test_a_text_field_takes_every_word_and_asks_to_quote_a_boolean_or_a_number(dotted, algorithm, word, how,
                                                                               tmp_path):
    if word in ("true", "false", "True", "FALSE", "1e3", "010"):
        with pytest.raises(ScenarioError) as info:
            _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert info.value.field == _field(dotted) and "put the value in quotes" in info.value.message
    elif word in ("null", "~"):
        with pytest.raises(ScenarioError) as info:
            _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert info.value.field == _field(dotted)
    elif dotted == "map" and how == "file":  # a file's map must exist: the word is read as text, and named
        with pytest.raises(MapError) as info:
            _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert info.value.field == "map" and f"unknown map '{word}'" in info.value.message
    else:
        assert _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted) == word


@pytest.mark.parametrize("how", ["file", "set"])
@pytest.mark.parametrize("word", WORDS)
@pytest.mark.parametrize(("dotted", "algorithm"), BOOL_FIELDS, ids=[f"{d}-{a}" for d, a in BOOL_FIELDS])
def test_a_boolean_field_takes_true_false_and_the_yes_no_on_off_words(dotted, algorithm, word, how, tmp_path):
    if word.lower() in TRUE_WORDS | FALSE_WORDS:
        got = _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert got is (word.lower() in TRUE_WORDS)
    else:
        with pytest.raises(ScenarioError) as info:
            _value(_scenario(algorithm, dotted, word, how, tmp_path), dotted)
        assert info.value.field == dotted and "give true or false" in info.value.message


@pytest.mark.parametrize("value", ["1", "0", "t", "f", "'1'"])
def test_a_boolean_field_refuses_numbers_and_letters(value):
    with pytest.raises(ScenarioError) as info:
        load_scenario("self-spreading-6x6", dict([parse_override(f"sim.stop_when_settled={value}")]))
    assert info.value.field == "sim.stop_when_settled"


def test_a_sweep_file_takes_the_words_unquoted(tmp_path):
    path = tmp_path / "sweep.yaml"
    path.write_text("name: words\nbase: self-spreading-6x6\n"
                    "overrides: {sim.time_limit: 3, sim.stop_when_settled: no}\n"
                    "grid:\n  algorithm.params.triangular: [off, none, local]\n  sim.coverage_target: [off, 0.9]\n"
                    "points:\n  - {radio.packet_loss: yes, sim.robot_collisions: off, on: 1}\n"
                    "seeds: 1\n")
    with pytest.raises(ScenarioError) as info:  # 'on' is a key (YAML 1.1 made it True), and not a field
        load_sweep(path)
    assert info.value.field == "points[0].on"
    path.write_text(path.read_text().replace(", on: 1", ""))
    sweep = load_sweep(path)
    assert [p.overrides for p in sweep.points[:2]] == [
        {"algorithm.params.triangular": "off", "sim.coverage_target": "off"},
        {"algorithm.params.triangular": "off", "sim.coverage_target": 0.9}]
    first, last = sweep.points[0].scenario, sweep.points[-1].scenario
    assert first["algorithm"]["params"]["triangular"] == "off" and first["sim"]["coverage_target"] == "off"
    assert first["sim"]["stop_when_settled"] is False
    assert last["radio"]["packet_loss"] is True and last["sim"]["robot_collisions"] is False


def _map(folder: Path, **values: str) -> Path:
    from PIL import Image

    Image.new("L", (4, 4), 255).save(folder / "m.png")
    entries = {"image": "m.png", "resolution": "0.5", "origin": "[0, 0, 0]", "negate": "0",
               "occupied_thresh": "0.65", "free_thresh": "0.196", **values}
    path = folder / "m.yaml"
    path.write_text("".join(f"{k}: {v}\n" for k, v in entries.items()))
    return path


@pytest.mark.parametrize(("negate", "negated"), [("no", False), ("off", False), ("false", False), ("0", False),
                                                 ("yes", True), ("On", True), ("true", True), ("1", True)])
def test_a_map_file_is_read_by_the_same_reader(negate, negated, tmp_path):
    omap = load_map_yaml(_map(tmp_path, negate=negate, resolution="5e-1"))  # YAML 1.1 read 5e-1 as a string
    assert omap.resolution == 0.5
    assert (omap.cells == 0).all() != negated  # white is free unless negated


def test_a_map_file_with_a_key_twice_or_too_deep_is_one_map_error(tmp_path):
    path = _map(tmp_path)
    path.write_text(path.read_text() + "resolution: 0.1\n")
    with pytest.raises(MapError, match=r"^map: key 'resolution' appears twice in '.*m.yaml' \(lines 2 and 7\)"):
        load_map_yaml(path)
    path = _map(tmp_path, licence="[" * 3000)
    with pytest.raises(MapError, match=r"^map: '.*m.yaml' is not valid YAML at line 7 \(lists and mappings nested"):
        load_map_yaml(path)


DEEP = "[" * 300 + "]" * 300
DEEPER = "[" * 5000


def _one_line_refusal(code: int, err: str, words: str) -> str:
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("amronet: error: "), err[-2000:]
    assert words in lines[0] and len(lines[0]) < 300 and "Traceback" not in err, lines[0][:500]
    return lines[0]


@pytest.mark.parametrize("text", [DEEP, DEEPER])
def test_deep_nesting_in_a_scenario_file_or_a_set_value_is_one_line(text, tmp_path, capsys):
    sc = tmp_path / "deep.yaml"
    sc.write_text(f"map: open-6x6\nbase_stations: [{{x: 0, y: 0}}]\ndescription: {text}\n")
    out = tmp_path / "o"
    line = _one_line_refusal(main(["run", str(sc), "--out", str(out)]), capsys.readouterr().err,
                             "nested deeper than 100 levels")
    assert line.startswith("amronet: error: scenario: ") and not out.exists()
    line = _one_line_refusal(main(["run", "--preset", "self-spreading-6x6", "--out", str(out), "--set",
                                   f"algorithm.params.x={text}"]), capsys.readouterr().err,
                             "nested deeper than 100 levels")
    assert line.startswith("amronet: error: algorithm.params.x: value '[[[[") and not out.exists()


def test_deep_nesting_in_a_sweep_file_or_its_map_is_one_line(tmp_path, capsys):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"name: deep\nbase: self-spreading-6x6\nseeds: 1\npoints: [{{description: {DEEP}}}]\n")
    store = tmp_path / "s.sqlite"
    _one_line_refusal(main(["sweep", str(sweep), "--store", str(store)]), capsys.readouterr().err,
                      "nested deeper than 100 levels")
    _map(tmp_path, licence=DEEPER)  # the sweep's scenario hash reads the map file before the map is loaded
    sweep.write_text("name: deep\nbase: {map: m.yaml, base_stations: [{x: 0.5, y: 0.5}]}\nseeds: 1\n")
    _one_line_refusal(main(["sweep", str(sweep), "--store", str(store)]), capsys.readouterr().err,
                      "m.yaml' is not valid YAML at line 7 (lists and mappings nested deeper than 100 levels)")
    assert not store.exists()


def test_the_deepest_nesting_allowed_passes_through_every_check_as_one_line(tmp_path, capsys):
    deepest = "[" * 99 + "]" * 99  # inside {description: ...}: 100 levels
    out = tmp_path / "o"
    _one_line_refusal(main(["run", "--preset", "self-spreading-6x6", "--out", str(out), "--set",
                            f"description={deepest}", "--set", "radio.r_c=1.2"]), capsys.readouterr().err,
                      "description: input should be a valid string (got list)")
    sweep = tmp_path / "sweep.yaml"
    deepest = "[" * 98 + "]" * 98  # the list of values of a key of grid: 100 levels
    sweep.write_text(f"name: deep\nbase: self-spreading-6x6\nseeds: 1\ngrid: {{description: {deepest}}}\n")
    _one_line_refusal(main(["sweep", str(sweep), "--store", str(tmp_path / "s.sqlite")]), capsys.readouterr().err,
                      "grid.description: input should be a valid string (got list)")


def test_deep_nesting_through_the_console_script(tmp_path):
    exe = Path(sys.executable).with_name("amronet")
    proc = subprocess.run([str(exe), "run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "o"),
                           "--set", f"sim.coverage_target={DEEPER}"], capture_output=True, text=True)
    _one_line_refusal(proc.returncode, proc.stderr, "sim.coverage_target: value '[[[[")
