"""``reproduce buildings --optimum``: the table gains the optimum per building and radio, and each cell's ratio."""

import csv
import io
from types import SimpleNamespace

import pytest

import amronet.optimum.stored as stored
from amronet.cli import main
from amronet.errors import AmronetError
from amronet.experiments import buildings, buildings_optimum
from amronet.experiments.buildings import run_buildings
from amronet.experiments.buildings_optimum import optimum_radio, solve_building_optima
from amronet.experiments.common import csv_text
from amronet.experiments.options import RunOptions
from amronet.optimum import find_optimum
from amronet.optimum.stored import optimum_key, optimum_problem
from amronet.sweeps.store import ResultStore

SMALL = {"buildings": ("cave",), "rules": ("last-reference",), "radios": ("unit-disk",), "stocks": (None,), "runs": 1}
"""One cell: the cave, the paper's rule, the unit disk, one short run; the optimum on a lattice of 2 m (r_c 4 m)."""

OPT_COLUMNS = ["optimum_best", "optimum_bound", "optimum_gap", "optimum_optimal", "optimum_radio", "optimum_spacing_m",
               "optimum_time_limit_s", "relays_to_optimum_best", "relays_to_optimum_bound"]


def _options(store, **changes):
    return RunOptions(**{"time_limit": 20.0, "workers": 1, "show_progress": False, "store": store, **changes})


def test_buildings_with_the_optimum_adds_its_columns_and_without_it_writes_what_it_wrote(tmp_path, monkeypatch):
    store = tmp_path / "results.sqlite"
    report = run_buildings(tmp_path / "opt", **SMALL, options=_options(store, optimum=1.0, optimum_spacing=2.0))
    [e] = report["table"]
    assert list(e)[-len(OPT_COLUMNS):] == OPT_COLUMNS
    assert 0 < e["optimum_bound"] <= e["optimum_best"] and e["optimum_spacing_m"] == 2.0
    assert e["optimum_time_limit_s"] == 1.0 and e["optimum_radio"] == "unit-disk"
    assert e["relays_to_optimum_best"] == e["relays_mean"] / e["optimum_best"]
    assert e["relays_to_optimum_bound"] == e["relays_mean"] / e["optimum_bound"]
    assert e["optimum_optimal"] == (e["optimum_gap"] == 0.0)
    [row] = csv.DictReader(io.StringIO((tmp_path / "opt" / "buildings_table.csv").read_text()))
    assert int(row["optimum_best"]) == e["optimum_best"] and float(row["relays_to_optimum_best"]) == pytest.approx(
        e["relays_to_optimum_best"])
    md = report["markdown"]
    assert "## Against the optimum" in md and f"| cave (4 m) | unit-disk | unlimited | 2 | {e['optimum_best']} / " in md
    assert f"{e['relays_to_optimum_best']:.2f}x" in md and "upper bound on the true optimum" in md
    assert "ratio to the bound the high side" in md and "mean path loss" in md

    # without the optimum (the same run, from the store): the files it wrote before, not a byte more
    plain = run_buildings(tmp_path / "plain", **SMALL, options=_options(store))
    assert "optimum" not in plain["markdown"] and md.startswith(plain["markdown"] + "\n## Against the optimum")
    assert plain["table"] == [{k: v for k, v in e.items() if k not in OPT_COLUMNS}]
    assert (tmp_path / "plain" / "buildings_table.csv").read_text() == csv_text(plain["table"])
    for name in ("buildings_runs.csv", "buildings.md"):
        assert (tmp_path / "plain" / name).read_text() != "" and (tmp_path / "opt" / name).read_text().startswith(
            (tmp_path / "plain" / name).read_text())
    assert (tmp_path / "plain" / "buildings.png").read_bytes() != (tmp_path / "opt" / "buildings.png").read_bytes()

    # a rerun loads the optimum from the store
    def no_solver(*args, **kwargs):
        raise AssertionError("solved again")

    monkeypatch.setattr(stored, "find_optimum", no_solver)
    again = run_buildings(tmp_path / "opt", **SMALL, options=_options(store, optimum=1.0, optimum_spacing=2.0))
    assert again["table"] == report["table"] and again["markdown"] == md


def test_a_radio_with_shadowing_is_compared_with_its_mean_path_loss(monkeypatch, capsys):
    asked = []

    def fake(map_ref, bases, r_c, spacing, *, radio, time_limit, store):
        asked.append((map_ref, bases, r_c, spacing, radio, time_limit))
        return SimpleNamespace(count=5, lower=4, from_store=False, seconds={"total": 0.5}, spacing=spacing)

    monkeypatch.setattr(buildings_optimum, "find_or_load_optimum", fake)
    optima = solve_building_optima(("cave",), ("unit-disk", "multi-wall"), 7.0, None, None, True)
    assert set(optima) == {("cave", "unit-disk"), ("cave", "multi-wall")}
    assert asked == [("cave", [(-6.4, -6.4)], 4.0, 2.0, None, 7.0),
                     ("cave", [(-6.4, -6.4)], 4.0, 2.0, {"model": "multi-wall", "shadowing_db": 0.0}, 7.0)]
    assert buildings.RADIOS["multi-wall"]["shadowing_db"] == 4.0  # the runs keep theirs
    assert optimum_radio("multi-wall")[1] == "multi-wall, mean path loss"
    assert optimum_radio("unit-disk") == (None, "unit-disk")
    err = capsys.readouterr().err
    assert "multi-wall: its shadowing differs from run to run, so the optimum is solved for its mean path loss" in err
    assert "optimum cave, r_c 4 m, multi-wall: 5 routers, proven bound 4, 2 m lattice (0 s)" in err


def _too_coarse(coarsest):
    """A fake solver whose lattices coarser than ``coarsest`` cannot cover the map, as walls make them."""
    asked = []

    def fake(map_ref, bases, r_c, spacing, *, radio, time_limit, store):
        asked.append(spacing)
        if spacing > coarsest:
            raise AmronetError(f"--spacing: 9 reachable cells can never be covered on the {spacing:g} m lattice; use a "
                               "finer spacing")
        return SimpleNamespace(count=5, lower=4, from_store=False, seconds={"total": 0.5}, spacing=spacing)

    return fake, asked


def test_the_default_lattice_goes_finer_where_walls_cut_its_links(monkeypatch, capsys):
    fake, asked = _too_coarse(1.0)
    monkeypatch.setattr(buildings_optimum, "find_or_load_optimum", fake)
    optima = solve_building_optima(("cave",), ("multi-wall",), 7.0, None, None, True)
    assert asked == [2.0, 1.0] and optima[("cave", "multi-wall")].spacing == 1.0
    assert "optimum cave, multi-wall: 9 reachable cells can never be covered on the 2 m lattice; use a finer " \
           "spacing; trying 1 m" in capsys.readouterr().err
    fake, asked = _too_coarse(0.1)  # none of r_c / 2, / 4, / 8 will do
    monkeypatch.setattr(buildings_optimum, "find_or_load_optimum", fake)
    with pytest.raises(AmronetError) as info:
        solve_building_optima(("cave",), ("multi-wall",), 7.0, None, None, False)
    assert str(info.value) == ("--optimum-spacing: cave, multi-wall: 9 reachable cells can never be covered on the "
                               "0.5 m lattice; use a finer spacing (tried 2, 1, 0.5 m)")
    fake, asked = _too_coarse(1.0)  # a spacing given is kept
    monkeypatch.setattr(buildings_optimum, "find_or_load_optimum", fake)
    with pytest.raises(AmronetError, match=r"^--optimum-spacing: cave, multi-wall: 9 .* finer spacing$"):
        solve_building_optima(("cave",), ("multi-wall",), 7.0, 1.5, None, False)
    assert asked == [1.5]


def test_a_rerun_starts_at_the_lattice_the_store_holds(tmp_path, monkeypatch, capsys):
    store = tmp_path / "results.sqlite"
    radio = optimum_radio("multi-wall")[0]
    doc = find_optimum("obstacles-6x6", [(-2.5, -2.5)], 3.0, 1.5, time_limit=20).to_dict()  # any answer will do
    problem = optimum_problem("cave", [(-6.4, -6.4)], 4.0, 1.0, radio=radio, time_limit=7.0)
    with ResultStore(store) as rs:
        rs.record_optimum(optimum_key(problem), problem, doc)
    monkeypatch.setattr(stored, "find_optimum", lambda *a, **k: pytest.fail("solved, or tried the 2 m lattice"))
    opt = solve_building_optima(("cave",), ("multi-wall",), 7.0, None, store, True)[("cave", "multi-wall")]
    assert opt.from_store and opt.count == 4 and "trying" not in capsys.readouterr().err


def test_reproduce_buildings_passes_the_optimum_and_its_spacing(tmp_path, monkeypatch):
    got = []
    monkeypatch.setattr(buildings, "run_buildings",
                        lambda out_dir, options, **kw: got.append(options) or {"markdown": ""})
    assert main(["reproduce", "buildings", "--optimum", "--out", str(tmp_path / "a"), "-q"]) == 0
    assert main(["reproduce", "buildings", "--optimum", "9", "--optimum-spacing", "1.5", "--out", str(tmp_path / "b"),
                 "-q"]) == 0
    assert main(["reproduce", "buildings", "--out", str(tmp_path / "c"), "-q"]) == 0
    assert [(o.optimum, o.optimum_spacing) for o in got] == [(60.0, None), (9.0, 1.5), (None, None)]


@pytest.mark.parametrize(("args", "start"), [
    (["--optimum", "0"], "--optimum: must be a number of seconds > 0"),
    (["--optimum", "nan"], "--optimum: must be a number of seconds > 0"),
    (["--optimum", "--optimum-spacing", "0"], "--optimum-spacing: must be a finite number of metres > 0, got 0.0"),
    (["--optimum", "--optimum-spacing=-inf"], "--optimum-spacing: must be a finite number of metres > 0"),
    (["--optimum-spacing", "2"], "--optimum-spacing: only with --optimum"),
    (["--quick", "--optimum", "1", "--optimum-spacing", "0.01"], "--optimum-spacing: office-32x32, unit-disk: "),
])
def test_bad_optimum_options_are_one_line_and_nothing_is_written(args, start, tmp_path, capsys):
    assert main(["reproduce", "buildings", *args, "--out", str(tmp_path / "x"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"amronet: error: {start}") and len(err.splitlines()) == 1
    assert not (tmp_path / "x" / "buildings.md").exists()


def test_the_library_refuses_a_spacing_without_the_optimum(tmp_path):
    with pytest.raises(AmronetError, match=r"^--optimum-spacing: only with --optimum"):
        run_buildings(tmp_path / "x", **SMALL, options=_options(None, optimum_spacing=2.0))
    assert not (tmp_path / "x").exists()
