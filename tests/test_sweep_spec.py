import pytest
import yaml

from amronet.cli import main
from amronet.errors import AmronetError, ScenarioError
from amronet.scenario import load_scenario
from amronet.sweeps import load_sweep, resolve_scenario, scenario_hash, sweep_from_spec
from sweep_helpers import tiny_sweep, write_sweep


def test_grid_then_points_in_order_with_seeds():
    sweep = sweep_from_spec(tiny_sweep(grid={"radio.r_c": [0.8, 1.0], "algorithm.params.triangular": ["local",
                                                                                                      "global"]},
                                       points=[{"routers.count": 10}], seeds=3, seed_start=5))
    assert [p.overrides for p in sweep.points] == [
        {"radio.r_c": 0.8, "algorithm.params.triangular": "local"},
        {"radio.r_c": 0.8, "algorithm.params.triangular": "global"},
        {"radio.r_c": 1.0, "algorithm.params.triangular": "local"},
        {"radio.r_c": 1.0, "algorithm.params.triangular": "global"},
        {"routers.count": 10}]
    assert sweep.seeds == [5, 6, 7] and len(sweep.runs()) == 15
    assert sweep.keys == ["radio.r_c", "algorithm.params.triangular", "routers.count"]
    assert sweep.points[4].scenario["routers"]["count"] == 10
    assert all(p.scenario["sim"]["time_limit"] == 3.0 for p in sweep.points)


def test_without_grid_one_point_and_seed_list():
    sweep = sweep_from_spec({"name": "one", "base": "self-spreading-6x6", "seeds": [9, 2]})
    assert len(sweep.points) == 1 and sweep.points[0].overrides == {} and sweep.seeds == [9, 2]


def test_identical_points_are_one_run():
    sweep = sweep_from_spec(tiny_sweep(radii=(1.0,), points=[{"radio.r_c": 1.0}]))
    assert len(sweep.points) == 2 and sweep.points[0].hash == sweep.points[1].hash
    assert len(sweep.runs()) == 2  # 2 seeds, not 4


def test_hash_is_of_the_resolved_scenario():
    a = resolve_scenario(load_scenario("self-spreading-6x6"))
    b = resolve_scenario(load_scenario("self-spreading-6x6", {"algorithm.params": {}, "radio.r_c": 1}))
    c = resolve_scenario(load_scenario("self-spreading-6x6", {"radio.r_c": 1.01}))
    assert a["algorithm"]["params"]["loss_margin"] == 0.05  # defaults spelt out
    assert scenario_hash(a) == scenario_hash(b) != scenario_hash(c)


def _copy_builtin_map(folder, name="open-6x6"):
    from importlib import resources

    src = resources.files("amronet").joinpath("data", "maps")
    folder.mkdir(exist_ok=True)
    text = src.joinpath(f"{name}.yaml").read_bytes()
    (folder / "m.yaml").write_bytes(text)  # byte for byte: the image keeps its name
    image = yaml.safe_load(text)["image"]
    (folder / image).write_bytes(src.joinpath(image).read_bytes())
    return folder / "m.yaml"


def test_editing_a_map_file_in_place_changes_the_key(tmp_path):
    import os

    from PIL import Image

    from amronet.sweeps.identity import map_digest

    path = _copy_builtin_map(tmp_path / "maps")
    spec = tiny_sweep(radii=(1.0,), overrides={"sim.time_limit": 3.0, "map": str(path)})
    first = sweep_from_spec(spec).points[0].hash
    assert sweep_from_spec(spec).points[0].hash == first
    path.write_text(path.read_text())  # the same bytes, a new mtime: the same run
    assert sweep_from_spec(spec).points[0].hash == first
    png = path.parent / "open-6x6.png"
    img = Image.open(png)
    img.putpixel((5, 5), 0)
    img.save(png)
    second = sweep_from_spec(spec).points[0].hash
    assert second != first
    meta = yaml.safe_load(path.read_text())
    path.write_text(yaml.safe_dump({**meta, "occupied_thresh": 0.6}))
    os.utime(path, ns=(1, 1))
    third = sweep_from_spec(spec).points[0].hash
    assert third not in (first, second)
    # built-in maps: their shipped files are hashed, a name alone is not enough
    assert map_digest("open-6x6") == map_digest(str(_copy_builtin_map(tmp_path / "copy")))
    assert map_digest("open-6x6") != map_digest("office-32x32") != map_digest(str(tmp_path / "none.yaml"))


def test_a_sweep_on_an_edited_map_runs_again(tmp_path, capsys):
    import json

    from amronet.sweeps import ResultStore

    path = _copy_builtin_map(tmp_path / "maps")
    sweep = write_sweep(tmp_path / "s.yaml", tiny_sweep(radii=(1.0,), seeds=1,
                                                         overrides={"sim.time_limit": 3.0, "map": str(path)}))
    store = tmp_path / "r.sqlite"

    def run() -> tuple[int, int]:
        assert main(["sweep", str(sweep), "--store", str(store), "--workers", "1", "--json", "-q"]) == 0
        doc = json.loads(capsys.readouterr().out)
        return doc["already_in_store"], doc["done_now"]

    assert run() == (0, 1)
    assert run() == (1, 0)
    path.write_text(path.read_text().replace("negate: 0", "negate: 0\n# edited"))
    assert run() == (0, 1)
    with ResultStore(store) as st:
        assert len(st.runs()) == 2


def test_relative_paths_are_taken_from_the_sweep_file(tmp_path):
    (tmp_path / "sub").mkdir()
    sc = load_scenario("self-spreading-6x6").to_dict()
    (tmp_path / "sub" / "sc.yaml").write_text(yaml.safe_dump(sc))
    sweep = load_sweep(write_sweep(tmp_path / "s.yaml", {"name": "rel", "base": "sub/sc.yaml", "seeds": 1}))
    assert sweep.points[0].scenario["map"] == "open-6x6"
    inline = {**sc, "map": "maps/m.yaml"}
    with pytest.raises(ScenarioError, match=r"^base: map: map file .*maps/m.yaml' not found"):
        load_sweep(write_sweep(tmp_path / "t.yaml", {"name": "inline", "base": inline, "seeds": 1}))
    _copy_builtin_map(tmp_path / "maps")  # the map is loaded before anything runs, from the sweep file's folder
    sweep = load_sweep(write_sweep(tmp_path / "t.yaml", {"name": "inline", "base": inline, "seeds": 1}))
    assert sweep.points[0].scenario["map"] == str(tmp_path / "maps" / "m.yaml")


@pytest.mark.parametrize(("spec", "field"), [
    (tiny_sweep(grid={}), "grid"),
    (tiny_sweep(grid={"radio.r_c": []}), "grid.radio.r_c"),
    (tiny_sweep(grid={"radio.rc": [1.0]}), "grid.radio.rc"),
    (tiny_sweep(grid={"radio.r_c": [1.0, -1.0]}), "grid.radio.r_c"),
    (tiny_sweep(grid={"algorithm.name": ["telepathy"]}), "grid.algorithm.name"),
    (tiny_sweep(points=[{"routers.count": 3}, {"routers.cont": 3}]), "points[1].routers.cont"),
    (tiny_sweep(points=[]), "points"),
    (tiny_sweep(seeds=0), "seeds"),
    (tiny_sweep(seeds=[]), "seeds"),
    (tiny_sweep(seeds=[1, 1]), "seeds"),
    (tiny_sweep(seeds="five"), "seeds"),
    (tiny_sweep(seeds=[1, 2], seed_start=3), "seed_start"),
    (tiny_sweep(seeds=[2**64]), "seeds"),
    (tiny_sweep(seeds=[0, 2**63]), "seeds"),
    (tiny_sweep(seeds=2, seed_start=2**63 - 1), "seeds"),
    (tiny_sweep(seeds=1, seed_start=2**63), "seed_start"),
    (tiny_sweep(seeds=10**12), "seeds"),
    (tiny_sweep(seedz=3), "seedz"),
    (tiny_sweep(overrides={"sim.time_limt": 3}), "overrides.sim.time_limt"),
    (tiny_sweep(base="no-such-preset"), "base"),
    (tiny_sweep(base={"map": "open-6x6"}), "base"),
    (tiny_sweep(name=""), "name"),
])
def test_bad_sweeps_name_the_field(spec, field):
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec(spec)
    assert str(info.value).startswith(field + ":") or info.value.field.startswith(field)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("extra", "start"), [
    ({"grid": {"map": ["open-6x6", "nosuchmap"]}},
     "grid.map: 'nosuchmap' is neither a built-in map name (open-6x6, "),
    ({"points": [{"radio.r_c": 1.0}, {"map": "/nonexistent/map.yaml"}]},
     "points[1].map: map file '/nonexistent/map.yaml' not found"),
    ({"overrides": {"map": "/nonexistent/map.yaml"}}, "overrides.map: map file '/nonexistent/map.yaml' not found"),
    ({"base": {**load_scenario("self-spreading-6x6").to_dict(), "map": "nosuchmap"}, "grid": None},
     "base: map: 'nosuchmap' is neither a built-in map name"),
    ({"points": [{"base_stations": [{"x": 100, "y": 100}]}]},
     "points[0].base_stations[0]: (100, 100) is outside the map [-3, 3] x [-3, 3]; move it inside (at point 2: "),
    ({"grid": {"radio.r_c": [1.0], "base_stations.0.x": [0.0, 100]}},
     "grid.base_stations[0]: (100, 0) is outside the map"),
    ({"grid": {"map": ["open-6x6", "office-32x32"]}},
     "grid: point 1 (map = 'office-32x32'): base_stations[0]: (0, 0) is inside an obstacle"),
    ({"grid": {"routers.count": [30, 3000]}},
     "grid.routers.count: 3000 routers (radius 0.045 m) need"),
    ({"overrides": {"sim.time_limit": 3.0, "base_stations.0.x": 100}},
     "overrides.base_stations[0]: (100, 0) is outside the map"),
])
def test_points_that_cannot_start_are_caught_before_running(extra, start):
    spec = {k: v for k, v in tiny_sweep(seeds=1, **extra).items() if v is not None}
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec(spec)
    assert str(info.value).startswith(start), str(info.value)
    assert "\n" not in str(info.value)


def test_each_distinct_start_is_set_up_once(monkeypatch):
    import amronet.sweeps.check as check

    started = []
    real = check._start
    monkeypatch.setattr(check, "_start", lambda sc, seed, maps: (started.append(sc["radio"]["r_c"]),
                                                                 real(sc, seed, maps)))
    sweep_from_spec(tiny_sweep(grid={"radio.r_c": [0.8, 1.0], "sim.time_limit": [1.0, 2.0, 3.0]}, seeds=3))
    assert started == [0.8, 1.0]


def test_sweeping_the_algorithm_drops_the_base_params(tmp_path, capsys):
    import json

    spec = tiny_sweep(radii=(1.0,), seeds=1, grid={"algorithm.name": ["self-spreading", "dssa"]},
                      points=[{"algorithm.name": "dssa", "algorithm.params.obstacle_forces": False},
                              {"algorithm.params.triangular": "global"}])
    sweep = sweep_from_spec(spec)
    algos = [p.scenario["algorithm"] for p in sweep.points]
    assert [a["name"] for a in algos] == ["self-spreading", "dssa", "dssa", "self-spreading"]
    assert algos[0]["params"]["triangular"] == "local" and algos[3]["params"]["triangular"] == "global"
    assert "triangular" not in algos[1]["params"] and algos[1]["params"]["obstacle_forces"] is True
    assert algos[2]["params"]["obstacle_forces"] is False
    # the sweep's fixed overrides switch the algorithm the same way
    fixed = sweep_from_spec(tiny_sweep(seeds=1, overrides={"sim.time_limit": 3.0, "algorithm.name": "dssa"}))
    assert all(p.scenario["algorithm"]["name"] == "dssa" for p in fixed.points)
    path = write_sweep(tmp_path / "algo.yaml", tiny_sweep(radii=(1.0,), seeds=1,
                                                          grid={"algorithm.name": ["self-spreading", "dssa"]}))
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--workers", "1", "--json", "-q"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [(p["algorithm.name"], p["done"]) for p in doc["points"]] == [("self-spreading", 1), ("dssa", 1)]


BAD_FILES = {
    "unknown-key": "name: x\nbase: self-spreading-6x6\nseeds: 2\ngrdi: {radio.r_c: [1]}\n",
    "empty-grid": "name: x\nbase: self-spreading-6x6\nseeds: 2\ngrid: {}\n",
    "zero-seeds": "name: x\nbase: self-spreading-6x6\nseeds: 0\n",
    "seed-too-big": "name: x\nbase: self-spreading-6x6\nseeds: [18446744073709551616]\n",
    "seeds-past-the-top": "name: x\nbase: self-spreading-6x6\nseeds: 2\nseed_start: 9223372036854775807\n",
    "bad-override": "name: x\nbase: self-spreading-6x6\nseeds: 1\ngrid: {routers.count: [5, many]}\n",
    "not-yaml": "name: [x\n",
    "not-a-mapping": "- 1\n- 2\n",
    "missing-map-file": "name: x\nbase: self-spreading-6x6\nseeds: 1\npoints: [{map: /nonexistent/map.yaml}]\n",
    "unknown-map-name": "name: x\nbase: self-spreading-6x6\nseeds: 1\ngrid: {map: [open-6x6, nosuchmap]}\n",
    "base-station-off-the-map": "name: x\nbase: self-spreading-6x6\nseeds: 1\n"
                                "points: [{base_stations: [{x: 100, y: 100}]}]\n",
    "empty": "",
}
BAD_FILE_ERRORS = {
    "missing-map-file": "points[0].map: map file '/nonexistent/map.yaml' not found",
    "unknown-map-name": "grid.map: 'nosuchmap' is neither a built-in map name",
    "base-station-off-the-map": "points[0].base_stations[0]: (100, 100) is outside the map",
    "empty": "sweep: '{bad}' is empty",
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_sweep_file_is_one_line_and_leaves_the_store_untouched(tmp_path, capsys, case):
    store = tmp_path / "results.sqlite"
    assert main(["sweep", str(write_sweep(tmp_path / "ok.yaml", tiny_sweep(seeds=1))), "--store", str(store),
                 "--workers", "1", "-q"]) == 0
    before = store.read_bytes()
    capsys.readouterr()
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD_FILES[case])
    assert main(["sweep", str(bad), "--store", str(store), "--workers", "1", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("amronet: error: ") and len(err.strip().splitlines()) == 1
    if case in BAD_FILE_ERRORS:
        assert err.startswith("amronet: error: " + BAD_FILE_ERRORS[case].format(bad=bad)), err
    assert store.read_bytes() == before
    assert main(["sweep", str(bad), "--store", str(tmp_path / "new.sqlite"), "--workers", "1", "-q"]) == 2
    assert not (tmp_path / "new.sqlite").exists()


def test_the_largest_seed_runs_and_a_larger_one_creates_no_store(tmp_path, capsys):
    top = tiny_sweep(seeds=1, seed_start=2**63 - 1, radii=(1.0,))
    assert sweep_from_spec(top).seeds == [2**63 - 1]
    store = tmp_path / "r.sqlite"
    assert main(["sweep", str(write_sweep(tmp_path / "top.yaml", top)), "--store", str(store), "--workers", "1",
                 "-q"]) == 0
    bad = tmp_path / "big.yaml"
    bad.write_text("name: x\nbase: self-spreading-6x6\nseeds: [18446744073709551616]\n")
    assert main(["sweep", str(bad), "--store", str(tmp_path / "new.sqlite"), "--workers", "1", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: seeds: seed 18446744073709551616 is above the largest seed 2**63 - 1")
    assert len(err.splitlines()) == 1 and not (tmp_path / "new.sqlite").exists()


def test_missing_sweep_file(tmp_path, capsys):
    assert main(["sweep", str(tmp_path / "nope.yaml"), "--store", str(tmp_path / "r.sqlite")]) == 2
    assert "no sweep file" in capsys.readouterr().err and not (tmp_path / "r.sqlite").exists()


def test_bad_workers_is_one_line(tmp_path, capsys):
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(tmp_path / "r.sqlite"), "--workers", "0"]) == 2
    assert "--workers" in capsys.readouterr().err
    with pytest.raises(AmronetError, match="--cluster"):
        from amronet.sweeps import make_executor

        make_executor(cluster="slurm")


def test_a_store_that_is_not_a_database_is_one_line_and_untouched(tmp_path, capsys):
    store = tmp_path / "results.sqlite"
    store.write_text("my notes, not a database\n")
    path = write_sweep(tmp_path / "s.yaml", tiny_sweep())
    assert main(["sweep", str(path), "--store", str(store), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert "--store" in err and "not a SQLite database" in err and len(err.strip().splitlines()) == 1
    assert store.read_text() == "my notes, not a database\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.sqlite", "s.yaml"]


def test_a_sweep_file_reads_exponents_and_refuses_a_key_twice(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("name: t\nbase: self-spreading-6x6\noverrides: {sim.time_limit: 3e0}\n"
                    "grid: {radio.r_c: [8e-1, 1E0]}\nseeds: 1\n")
    sweep = load_sweep(path)
    assert [p.overrides["radio.r_c"] for p in sweep.points] == [0.8, 1.0]
    path.write_text("name: t\nbase: self-spreading-6x6\ngrid: {radio.r_c: [0.8]}\nseeds: 1\ngrid: {radio.r_c: [1]}\n")
    with pytest.raises(ScenarioError) as info:
        load_sweep(path)
    assert str(info.value) == f"sweep: key 'grid' appears twice in {str(path)!r} (lines 3 and 5); keep one"
