"""Optima kept in the result store like runs: solved once, loaded after, keyed by the whole problem."""

import json
import sqlite3

import numpy as np
import pytest
from PIL import Image

import amronet.optimum.stored as stored
from amronet.cli import main
from amronet.errors import AmronetError
from amronet.optimum import find_optimum, find_or_load_optimum
from amronet.optimum.stored import optimum_key, optimum_problem
from amronet.sweeps.store import ResultStore


@pytest.fixture
def corridor_map(tmp_path):
    """A corridor 4.9 m x 0.5 m (a ROS map_server YAML and PNG); its optimum at r_c 1 m is 4 routers."""
    free = np.zeros((12, 100), dtype=bool)
    free[1:-1, 1:-1] = True
    Image.fromarray(np.where(np.flipud(free), 254, 0).astype(np.uint8), mode="L").save(tmp_path / "corridor.png")
    (tmp_path / "corridor.yaml").write_text("image: corridor.png\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\n"
                                            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return str(tmp_path / "corridor.yaml")


@pytest.fixture
def solves(monkeypatch):
    """The calls of the solver (``find_optimum``) through the store, counted."""
    calls = []

    def counted(*args, **kwargs):
        calls.append((args, kwargs))
        return find_optimum(*args, **kwargs)

    monkeypatch.setattr(stored, "find_optimum", counted)
    return calls


def _solve(corridor_map, store, **changes):
    kwargs = {"time_limit": 20.0, "store": store, **changes}
    spacing = kwargs.pop("spacing", 0.25)
    return find_or_load_optimum(corridor_map, [(0.3, 0.3)], 1.0, spacing, **kwargs)


def test_a_second_call_with_the_same_store_loads_the_answer_and_does_not_solve(tmp_path, corridor_map, solves):
    store = tmp_path / "results.sqlite"
    first = _solve(corridor_map, store)
    assert len(solves) == 1 and not first.from_store and first.count == first.lower == 4
    again = _solve(corridor_map, store)
    assert len(solves) == 1 and again.from_store  # not solved again
    assert again.to_dict() == json.loads(json.dumps(first.to_dict()))  # the identical answer
    assert np.allclose(again.routers, first.routers) and (again.count, again.lower) == (4, 4)
    with sqlite3.connect(store) as db:
        rows = db.execute("SELECT key, instance, amronet_version FROM optima").fetchall()
    assert len(rows) == 1 and json.loads(rows[0][1])["spacing_m"] == 0.25


def test_a_different_spacing_or_time_limit_is_another_problem(tmp_path, corridor_map, solves):
    store = tmp_path / "results.sqlite"
    _solve(corridor_map, store)
    _solve(corridor_map, store, spacing=0.5)
    assert len(solves) == 2
    _solve(corridor_map, store, time_limit=10.0)
    assert len(solves) == 3
    _solve(corridor_map, store, spacing=0.5)
    assert len(solves) == 3
    with sqlite3.connect(store) as db:
        assert db.execute("SELECT COUNT(*) FROM optima").fetchone()[0] == 3


def test_the_key_spells_out_defaults_and_keeps_the_seed_only_for_a_shadowing_radio(corridor_map):
    def key(**kw):
        return optimum_key(optimum_problem(corridor_map, [(0.3, 0.3)], 1.0, 0.25, **kw))

    assert key() == key(radio={"model": "unit-disk"}) == key(seed=7)  # the unit disk draws no random field
    assert key() != key(radio={"model": "multi-wall"})
    shadowed = {"model": "log-distance", "shadowing_db": 4.0}
    assert key(radio=shadowed) != key(radio=shadowed, seed=1)
    assert key() != key(coarse=False)
    assert key() != optimum_key(optimum_problem(corridor_map, [(0.35, 0.3)], 1.0, 0.25))
    assert key() != optimum_key(optimum_problem(corridor_map, [(0.3, 0.3)], 1.1, 0.25))


def test_an_edited_map_file_is_another_problem(tmp_path, corridor_map):
    before = optimum_key(optimum_problem(corridor_map, [(0.3, 0.3)], 1.0, 0.25))
    yaml = tmp_path / "corridor.yaml"
    yaml.write_text(yaml.read_text().replace("free_thresh: 0.196", "free_thresh: 0.2"))
    assert optimum_key(optimum_problem(corridor_map, [(0.3, 0.3)], 1.0, 0.25)) != before


@pytest.mark.parametrize(("changes", "option"), [
    ({"spacing": 0.0}, "--spacing"), ({"time_limit": -1.0}, "--time-limit"),
    ({"radio": {"model": "smoke-signals"}}, "--radio")])
def test_bad_input_with_a_store_is_one_line_and_stores_nothing(tmp_path, corridor_map, changes, option):
    store = tmp_path / "results.sqlite"
    with pytest.raises(AmronetError, match=f"^{option}:"):
        _solve(corridor_map, store, **changes)
    assert not store.exists()


def test_a_store_from_before_optima_gains_the_table(tmp_path, corridor_map, solves):
    store = tmp_path / "old.sqlite"
    ResultStore(store).close()
    with sqlite3.connect(store) as db:
        db.execute("DROP TABLE optima")
    with ResultStore(store, must_exist=True) as rs:  # read only: nothing is stored and nothing is added
        assert rs.stored_optimum("no-such-key") is None
    _solve(corridor_map, store)
    _solve(corridor_map, store)
    assert len(solves) == 1


def test_cli_optimum_with_a_store_loads_the_answer_and_still_draws_it(tmp_path, corridor_map, solves, capsys):
    store = tmp_path / "results.sqlite"
    args = ["optimum", "--map", corridor_map, "--base", "0.3,0.3", "--rc", "1", "--spacing", "0.25",
            "--time-limit", "20", "--store", str(store)]
    assert main([*args, "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main([*args, "--out", str(tmp_path / "opt")]) == 0
    captured = capsys.readouterr()
    assert len(solves) == 1 and "loaded from the store" in captured.err
    assert "best placement: 4 routers" in captured.out
    assert json.loads((tmp_path / "opt" / "optimum.json").read_text()) == first
    assert Image.open(tmp_path / "opt" / "optimum.png").size[0] > 400


def test_cli_optimum_refuses_a_store_that_is_not_one_before_solving(tmp_path, corridor_map, solves, capsys):
    notes = tmp_path / "notes.txt"
    notes.write_text("mine")
    assert main(["optimum", "--map", corridor_map, "--base", "0.3,0.3", "--rc", "1", "--store", str(notes)]) == 2
    assert capsys.readouterr().err.strip().startswith("amronet: error: --store:")
    assert notes.read_text() == "mine" and not solves


def test_plan_with_optimum_keeps_it_in_the_plans_store(tmp_path, solves, capsys):
    args = ["plan", "--map", "obstacles-6x6", "--base=-2.5,-2.5", "--rc", "3", "--runs", "1", "--workers", "1",
            "--time-limit", "300", "--optimum", "10", "--store", str(tmp_path / "plan.sqlite"), "--json"]
    assert main(args) == 0
    first = json.loads(capsys.readouterr().out)["optimum"]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["optimum"] == first and len(solves) == 1
