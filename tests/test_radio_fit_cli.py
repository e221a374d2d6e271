"""amronet radio-fit end to end: bad input is one line and exit 2, the BLE flat's fit as a regression test."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from amronet.cli.main import main

FLAT = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ble-flat"

ANCHORS = "id,x,y,z\n1,-2.0,-2.0,2.0\n2,2.0,2.0,2.0\n"
GOOD = "point,x,y,anchor,rssi_dbm\n" + "".join(
    f"{i},{-2.5 + 0.05 * i},{-2.4 + 0.04 * i},{a},{-50 - 0.3 * (i % 7) - 2 * a}\n" for i in range(100) for a in (1, 2))


def _run(tmp_path, rssi=GOOD, anchors=ANCHORS, extra=()):
    (tmp_path / "rssi.csv").write_text(rssi)
    (tmp_path / "anchors.csv").write_text(anchors)
    return main(["radio-fit", "--map", "open-6x6", "--anchors", str(tmp_path / "anchors.csv"), "--rssi",
                 str(tmp_path / "rssi.csv"), "--bootstrap", "20", "--no-pictures", "--out",
                 str(tmp_path / "fit"), *extra])


def test_good_input_writes_the_folder_and_the_same_seed_the_same_bytes(tmp_path, capsys):
    assert _run(tmp_path, extra=["--model", "all", "-q"]) == 0
    first = (tmp_path / "fit" / "fit.json").read_bytes()
    doc = json.loads(first)
    assert {f["model"] for f in doc["fits"]} == {"log-distance", "multi-wall"}
    assert [c["model"] for c in doc["comparison"]][:2] == ["log-distance", "multi-wall"]
    block = yaml.safe_load((tmp_path / "fit" / "radio.yaml").read_text())["radio"]
    assert block == doc["radio"]
    assert _run(tmp_path, extra=["--model", "all", "-q"]) == 0
    assert (tmp_path / "fit" / "fit.json").read_bytes() == first


@pytest.mark.parametrize(("rssi", "anchors", "needle"), [
    ("x,y,anchor\n1,1,1\n", ANCHORS, "no column 'rssi_dbm'"),
    ("", ANCHORS, "is empty"),
    ("x,y,anchor,rssi_dbm\n", ANCHORS, "no rows"),
    ("x,y,anchor,rssi_dbm\n1,1,1,nan\n", ANCHORS, "not finite"),
    ("x,y,anchor,rssi_dbm\n1,1,1,strong\n", ANCHORS, "not a number"),
    ("x,y,anchor,rssi_dbm\n1,1,7,-60\n", ANCHORS, "anchor '7' is not in --anchors"),
    ("x,y,anchor,rssi_dbm\n40,1,1,-60\n", ANCHORS, "off the map"),
    (GOOD, "id,x,y\n1,1,1\n1,2,2\n", "appears twice"),
    (GOOD, "id,x\n1,1\n", "no column 'y'"),
    ("point,x,y,anchor,rssi_dbm\n0,1,1,1,-60\n0,2,2,2,-61\n", ANCHORS, "two different positions"),
])
def test_bad_input_is_one_line_and_exit_2_and_writes_nothing(tmp_path, capsys, rssi, anchors, needle):
    assert _run(tmp_path, rssi, anchors) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error:") and needle in err and "\n" not in err, err
    assert not (tmp_path / "fit").exists()


def test_point_in_a_wall_is_refused(tmp_path, capsys):
    (tmp_path / "rssi.csv").write_text("x,y,anchor,rssi_dbm\n-2.99,0.01,1,-60\n")
    (tmp_path / "anchors.csv").write_text("id,x,y\n1,1.0,1.0\n")
    code = main(["radio-fit", "--map", "obstacles-6x6", "--anchors", str(tmp_path / "anchors.csv"),
                 "--rssi", str(tmp_path / "rssi.csv")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "in a wall or unknown space" in err and "\n" not in err


def test_missing_file_and_bad_options(tmp_path, capsys):
    assert _run(tmp_path, extra=["--folds", "1"]) == 2
    assert "--folds" in capsys.readouterr().err
    assert _run(tmp_path, extra=["--block-m", "0"]) == 2
    assert "--block-m: 0 must be a side in metres" in capsys.readouterr().err
    assert _run(tmp_path, extra=["--block-m", "50"]) == 2  # the positions span 5 m: one block
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --block-m: blocks of 50 m hold the positions in 1 blocks"), err
    assert "\n" not in err
    assert not (tmp_path / "fit").exists()
    code = main(["radio-fit", "--map", "open-6x6", "--anchors", str(tmp_path / "none.csv"), "--rssi", "x.csv"])
    assert code == 2 and "cannot read" in capsys.readouterr().err


def test_a_floor_above_readings_is_refused(tmp_path, capsys):
    assert _run(tmp_path, extra=["--floor-dbm", "-52"]) == 2  # the readings go down to -55.8 dBm
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --floor-dbm: -52 dBm is above "), err
    assert "the weakest is -55.8 dBm" in err and "\n" not in err
    assert not (tmp_path / "fit").exists()


@pytest.fixture
def flat() -> Path:
    if not (FLAT / "rssi.csv").is_file():
        pytest.skip("../shared/data/ble-flat is not beside the project")
    return FLAT


# Recorded with --model all --seed 0 (pooled constant, 3-D lengths, tag at 1.3 m).
RECORDED = {"log-distance": {"a_dbm": -47.356, "path_loss_exponent": 1.989, "shadowing_db": 6.963,
                             "shadowing_corr_m": 3.19},
            "multi-wall": {"a_dbm": -49.401, "path_loss_exponent": 0.975, "wall_db": 5.787, "shadowing_db": 5.966,
                           "shadowing_corr_m": 0.737}}


def test_ble_flat_fit_matches_the_recorded_values(flat, tmp_path, capsys):
    code = main(["radio-fit", "--map", str(flat / "flat.yaml"), "--anchors", str(flat / "anchors.csv"), "--rssi",
                 str(flat / "rssi.csv"), "--model", "all", "--bootstrap", "100", "--out", str(tmp_path / "fit")])
    assert code == 0
    doc = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert "CC BY 4.0" in doc["data"]["attribution"]
    for fit in doc["fits"]:
        for name, value in RECORDED[fit["model"]].items():
            lo, hi = fit["parameters"][name]["ci95"]
            assert lo <= value <= hi, (fit["model"], name, value, lo, hi)
    cv = {c["model"]: c["cv_rmse_db"] for c in doc["comparison"]}
    assert cv["multi-wall"] < cv["log-distance"] - 0.8
    assert cv["multi-wall per-anchor"] < cv["multi-wall"]
    # blocks of 3 x 0.74 m: held-out areas cost every model more than held-out positions, per-anchor most
    assert doc["cross_validation"]["block_m"] == 2.21 and doc["cross_validation"]["blocks"] == 12
    gap = {c["model"]: c["cv_rmse_db"] - c["cv_position_rmse_db"] for c in doc["comparison"]}
    assert 0.0 < gap["multi-wall"] < 0.3 and gap["log-distance per-anchor"] > 0.2, gap
    assert doc["chosen"] == "multi-wall"
    assert doc["radio"]["path_loss_exponent"] == 1.0  # the fitted 0.975 is below amronet's bound
    assert np.isclose(doc["radio"]["wall_db"], 5.75, atol=0.02)
    assert (tmp_path / "fit" / "fit.png").stat().st_size > 10_000
    assert "--set radio.wall_db=" in capsys.readouterr().out
