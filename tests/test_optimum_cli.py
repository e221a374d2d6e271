"""``amronet optimum`` on the command line: its files, and bad input as one line with exit status 2."""

import json

import numpy as np
import pytest
from PIL import Image

from amronet.cli import main
from amronet.optimum import find_optimum
from amronet.outputs.files import MANIFEST


def write_map(folder, free: np.ndarray, res: float = 0.05) -> str:
    """A ROS map_server YAML and PNG of ``free`` (row 0 at the bottom), in ``folder``; returns the YAML's path."""
    image = np.where(np.flipud(free), 254, 0).astype(np.uint8)
    Image.fromarray(image, mode="L").save(folder / "tiny.png")
    (folder / "tiny.yaml").write_text(f"image: tiny.png\nresolution: {res}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
                                      "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return str(folder / "tiny.yaml")


@pytest.fixture
def corridor_map(tmp_path):
    free = np.zeros((12, 100), dtype=bool)  # a corridor 4.9 m x 0.5 m
    free[1:-1, 1:-1] = True
    return write_map(tmp_path, free)


def test_optimum_writes_json_and_picture_and_prints_the_bound(tmp_path, corridor_map, capsys):
    out = tmp_path / "opt"
    args = ["optimum", "--map", corridor_map, "--base", "0.3,0.3", "--rc", "1", "--spacing", "0.25",
            "--time-limit", "20", "--out", str(out)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "best placement: 4 routers" in text and "gap closed (optimal)" in text
    doc = json.loads((out / "optimum.json").read_text())
    assert doc["best"]["routers"] == 4 and doc["lower_bound"] == 4 and doc["optimal"] is True and doc["gap"] == 0
    assert len(doc["best"]["positions"]) == 4
    assert doc["verified"] == {"coverage": 1.0, "connected": True, "uncovered_cells": 0}
    assert set(doc["bounds"]) >= {"solver", "lp_relaxation", "set_cover", "hop_straight", "hop_lattice"}
    assert "upper bound on the optimum with routers anywhere" in doc["caveat"]
    assert doc["solver"]["name"].startswith("HiGHS") and doc["solver"]["time_limit_s"] == 20
    assert Image.open(out / "optimum.png").size[0] > 400
    assert sorted(p.name for p in out.iterdir()) == sorted([MANIFEST, "optimum.json", "optimum.png"])
    assert main([*args, "--json"]) == 0  # its own folder is replaced
    assert json.loads(capsys.readouterr().out)["best"]["routers"] == 4


def test_the_json_matches_the_library(corridor_map, capsys):
    assert main(["optimum", "--map", corridor_map, "--base", "0.3,0.3", "--rc", "1", "--spacing", "0.5",
                 "--time-limit", "10", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    opt = find_optimum(corridor_map, [(0.3, 0.3)], 1.0, 0.5, time_limit=10)
    assert doc["best"]["routers"] == opt.count and doc["lower_bound"] == opt.lower


@pytest.mark.parametrize(("extra", "option"), [
    (["--base", "0.0,0.0"], "--base"),                        # in the wall
    (["--base", "9,9"], "--base"),                            # off the map
    (["--base", "0.3,0.3", "--spacing", "0"], "--spacing"),
    (["--base", "0.3,0.3", "--spacing", "-1"], "--spacing"),
    (["--base", "0.3,0.3", "--spacing", "0.01"], "--spacing"),  # finer than the map's cells
    (["--base", "0.3,0.3", "--rc", "-2"], "--rc"),
    (["--base", "0.3,0.3", "--rc", "0.05"], "--rc"),           # under two cells
    (["--base", "0.3,0.3", "--rc", "1e9"], "--rc"),            # beyond the longest range amronet models
    (["--base", "0.3,0.3", "--time-limit", "0"], "--time-limit"),
    (["--base", "0.3,0.3", "--time-limit", "-5"], "--time-limit"),
    (["--base", "0.3,0.3", "--radio", "nosuch"], "--radio"),
    (["--base", "0.3,0.3", "--wall-db", "3"], "--wall-db"),    # the unit disk has no walls
    (["--base", "0.3"], "--base"),
    ([], "--base"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, corridor_map, capsys, extra, option):
    args = ["optimum", "--map", corridor_map, *(["--rc", "1"] if "--rc" not in extra else []), "--time-limit", "5",
            "--out", str(tmp_path / "never"), *extra]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"amronet: error: {option}") and "\n" not in err, err
    assert not (tmp_path / "never").exists()


def test_an_unknown_map_is_refused(capsys):
    assert main(["optimum", "--map", "nosuchmap", "--base", "1,1", "--rc", "4"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --map") and "\n" not in err


def test_space_no_router_can_reach_is_refused(tmp_path, capsys):
    free = np.zeros((40, 120), dtype=bool)  # a room, then a slot 4 cm wide (a router is 9 cm), then a room
    free[1:-1, 1:40] = True
    free[20, 40:80] = True
    free[1:-1, 80:-1] = True
    path = write_map(tmp_path, free, res=0.04)
    assert main(["optimum", "--map", path, "--base", "0.5,0.8", "--rc", "1", "--spacing", "0.25",
                 "--time-limit", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --spacing:") and "can never be covered" in err and "\n" not in err


def test_an_existing_folder_of_the_user_is_refused_before_the_search(tmp_path, corridor_map, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "thesis.tex").write_text("mine")
    assert main(["optimum", "--map", corridor_map, "--base", "0.3,0.3", "--rc", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --out:") and "thesis.tex" in err
    assert [p.name for p in out.iterdir()] == ["thesis.tex"]


def test_plan_with_optimum_adds_its_row_and_the_ratio(tmp_path, capsys):
    out = tmp_path / "plan"
    assert main(["plan", "--map", "obstacles-6x6", "--base=-2.5,-2.5", "--rc", "3", "--runs", "1", "--workers", "1",
                 "--time-limit", "300", "--optimum", "10", "--out", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["optimum"]["routers"] == 4 and doc["optimum"]["optimal"] is True and doc["optimum"]["spacing_m"] == 1.5
    assert json.loads((out / "plan.json").read_text())["optimum"] == doc["optimum"]
    md = (out / "plan.md").read_text()
    assert "| fewest on a 1.5 m lattice (amronet optimum, optimal) | 5 | 4 |" in md
    assert f"The recommendation is {doc['recommended_routers'] / 4:.2f} times the best placement" in md


def test_plan_refuses_a_bad_optimum_time_before_any_run(tmp_path, capsys):
    assert main(["plan", "--map", "obstacles-6x6", "--base=-2.5,-2.5", "--rc", "3", "--optimum", "0"]) == 2
    assert capsys.readouterr().err.strip().startswith("amronet: error: --optimum:")
