"""``reproduce fig5 --optimum``: the table gains the optimum and each count's ratio to it, through the store."""

import csv

import pytest
from PIL import Image

import amronet.optimum.stored as stored
from amronet.cli import main
from amronet.experiments import fig5
from amronet.experiments.fig5 import run_fig5
from amronet.experiments.options import RunOptions

SMALL = {"maps": ("open-32x32",), "radii": (10,), "agents": (2,), "starts": 1}
"""One map, one radius, one run: agents from the corner, the optimum on a lattice of 5 m (optimal in seconds)."""


def _options(store, **changes):
    return RunOptions(**{"time_limit": 3000.0, "workers": 1, "show_progress": False, "store": store, **changes})


def test_fig5_with_the_optimum_adds_its_columns_ratios_and_caveat_and_a_rerun_loads_it(tmp_path, monkeypatch):
    store = tmp_path / "results.sqlite"
    report = run_fig5(tmp_path / "f5", **SMALL, optimum_spacing=5.0, options=_options(store, optimum=20.0))
    e = report["table"][0]
    assert e["opt_optimal"] and e["opt_best_nodes"] == e["opt_bound_nodes"] == 9 and e["opt_gap"] == 0.0
    assert e["opt_spacing_m"] == 5.0 and e["opt_time_limit_s"] == 20.0
    assert e["ard_to_opt_best"] == pytest.approx(e["ard_mean"] / 9)
    assert e["r-strip_to_opt_best"] == pytest.approx(e["r-strip_placed"] / 9) == e["r-strip_to_opt_bound"]
    table = list(csv.DictReader((tmp_path / "f5" / "fig5_table.csv").open()))
    assert table[0]["opt_best_nodes"] == "9" and float(table[0]["square_to_opt_bound"]) == pytest.approx(1.0)
    md = (tmp_path / "f5" / "fig5_claims.md").read_text()
    assert "## Against the optimum" in md and "| open-32x32 | 10 | 5 | 9 / 9 (optimal) |" in md
    assert f"{e['ard_to_opt_best']:.2f}x" in md and "upper bound on the optimum with routers anywhere" in md
    assert "ARD stops at 99 % coverage" in md
    assert Image.open(tmp_path / "f5" / "fig5.png").size[0] > 400

    def no_solver(*args, **kwargs):
        raise AssertionError("solved again")

    monkeypatch.setattr(stored, "find_optimum", no_solver)
    again = run_fig5(tmp_path / "f5", **SMALL, optimum_spacing=5.0, options=_options(store, optimum=20.0))
    assert again["table"] == report["table"] and again["markdown"] == report["markdown"]


def test_fig5_without_the_optimum_has_none_of_it(tmp_path):
    report = run_fig5(tmp_path / "f5", **SMALL, options=_options(None))
    assert not any(k.startswith("opt_") or "_to_opt_" in k for k in report["table"][0])
    assert "optimum" not in report["markdown"]


def test_reproduce_fig5_passes_optimum_seconds_to_the_figure(tmp_path, monkeypatch):
    got = []
    monkeypatch.setattr(fig5, "run_fig5", lambda out_dir, options, **kw: got.append(options) or {"markdown": ""})
    assert main(["reproduce", "fig5", "--optimum", "--out", str(tmp_path / "a"), "-q"]) == 0
    assert main(["reproduce", "fig5", "--optimum", "30", "--out", str(tmp_path / "b"), "-q"]) == 0
    assert main(["reproduce", "fig5", "--out", str(tmp_path / "c"), "-q"]) == 0
    assert main(["reproduce", "fig5", "--optimum", "--optimum-spacing", "2.5", "--out", str(tmp_path / "d"), "-q"]) == 0
    assert [(o.optimum, o.optimum_spacing) for o in got] == [(60.0, None), (30.0, None), (None, None), (60.0, 2.5)]


@pytest.mark.parametrize("figure", ["fig7", "paper"])
@pytest.mark.parametrize("flag", [["--optimum"], ["--optimum-spacing", "2"]])
def test_figures_without_the_optimum_refuse_it_before_any_run(figure, flag, tmp_path, capsys):
    assert main(["reproduce", figure, *flag, "--out", str(tmp_path / "x"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"amronet: error: {flag[0]}: ") and "only fig5 and buildings compare with the optimum" in err
    assert len(err.splitlines()) == 1 and not (tmp_path / "x").exists()


def test_a_bad_optimum_time_is_one_line_before_any_run(tmp_path, capsys):
    assert main(["reproduce", "fig5", "--optimum", "0", "--out", str(tmp_path / "x"), "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("amronet: error: --optimum: must be a number of seconds > 0") and len(err.splitlines()) == 1
    assert not (tmp_path / "x" / "results.sqlite").exists()
