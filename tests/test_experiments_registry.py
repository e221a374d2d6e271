"""The figure registry of ``amronet reproduce``, its run options and the options a figure does not take."""

import dataclasses
import subprocess
import sys
import types
from pathlib import Path

import pytest

from amronet.cli import main
from amronet.errors import AmronetError
from amronet.experiments.options import RUN_OPTIONS, RunOptions
from amronet.experiments.registry import FIGURES, Figure, check_options
from amronet.experiments.runner import run_jobs
from amronet.registry import Registry


@pytest.fixture
def seen(monkeypatch):
    """Calls of the fake figure function ``amronet_fake_fig:run_fake``."""
    calls = []

    def fake(out_dir, figure="a", runs=1, options=None):
        calls.append({"out_dir": out_dir, "figure": figure, "runs": runs, "options": options})
        return {"markdown": f"# {figure}"}

    module = types.ModuleType("amronet_fake_fig")
    module.run_fake = fake
    monkeypatch.setitem(sys.modules, "amronet_fake_fig", module)
    return calls


def _fakes(monkeypatch, **without):
    """Replace the registry by f1 (taking every option) and f2 (without ``without``)."""
    from amronet.experiments import registry

    fakes = Registry("figure")
    fakes.add("f1", Figure("f1", "amronet_fake_fig:run_fake", kwargs={"figure": "f1"}))
    fakes.add("f2", Figure("f2", "amronet_fake_fig:run_fake", kwargs={"figure": "f2"}, without=without))
    monkeypatch.setattr(registry, "FIGURES", fakes)
    return fakes


def test_figures_are_a_registry_in_the_order_reproduce_all_runs_them():
    assert isinstance(FIGURES, Registry) and FIGURES.what == "figure"
    assert list(FIGURES) == ["fig5", "fig7", "fig10", "fig11", "buildings", "walks", "failures"]
    assert all(FIGURES[name].name == name for name in FIGURES)
    no_optimum = {"optimum": "only fig5 and buildings compare with the optimum",
                  "optimum_spacing": "only fig5 and buildings compare with the optimum"}
    no_baselines = {"baselines": "only fig10 and fig11 draw the Voronoi baselines"}
    assert FIGURES["fig10"].without == FIGURES["fig11"].without == {"explorer": "it runs no agents", **no_optimum}
    assert FIGURES["fig5"].without == no_baselines and FIGURES["fig7"].without == {**no_optimum, **no_baselines}
    assert FIGURES["buildings"].without == no_baselines
    assert [name for name in FIGURES if "optimum" not in FIGURES[name].without] == ["fig5", "buildings"]
    assert [name for name in FIGURES if "baselines" not in FIGURES[name].without] == ["fig10", "fig11"]


def test_figure_modules_are_imported_only_when_a_figure_runs():
    code = ("import sys; from amronet.cli.main import build_parser; build_parser(); "
            "print(sorted(m for m in sys.modules if m.startswith('amronet.experiments.fig')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_run_options_defaults_are_the_figures_old_defaults():
    o = RunOptions()
    assert (o.explorer, o.time_limit, o.workers, o.show_progress, o.seed, o.store, o.executor, o.retry_failed,
            o.optimum, o.optimum_spacing, o.baselines) == ("frontier", None, None, True, 0, None, None, False, None,
                                                           None, None)
    assert RUN_OPTIONS == ("explorer", "time_limit", "workers", "show_progress", "seed", "store", "executor",
                           "retry_failed", "optimum", "optimum_spacing", "baselines")
    assert o.time_limit_or(900.0) == 900.0 and RunOptions(time_limit=30.0).time_limit_or(900.0) == 30.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        o.workers = 2


def test_figure_run_builds_the_options_from_quick_and_the_given_options(tmp_path, seen):
    fig = Figure("b", "amronet_fake_fig:run_fake", kwargs={"figure": "b"}, quick={"runs": 2, "time_limit": 3.0})
    fig.run(tmp_path, quick=True, workers=3, explorer="x", time_limit=None)
    fig.run(tmp_path, quick=True, time_limit=5.0)  # a given option wins over quick's
    fig.run(tmp_path, store=tmp_path / "s.sqlite")
    assert [(s["out_dir"], s["figure"], s["runs"]) for s in seen] == [(tmp_path, "b", 2)] * 2 + [(tmp_path, "b", 1)]
    assert [s["options"] for s in seen] == [RunOptions(workers=3, explorer="x", time_limit=3.0),
                                           RunOptions(time_limit=5.0), RunOptions(store=tmp_path / "s.sqlite")]


def test_an_option_a_figure_does_not_take_is_an_error_and_nothing_runs(tmp_path, seen):
    fig = Figure("fig9", "amronet_fake_fig:run_fake", without={"explorer": "it runs no agents"})
    with pytest.raises(AmronetError) as info:
        fig.run(tmp_path, explorer="random")
    assert str(info.value) == "--explorer: fig9 does not take this option (it runs no agents)"
    fig.run(tmp_path, explorer=None, workers=1)  # not given: fine
    assert len(seen) == 1 and seen[0]["options"].explorer == "frontier"
    with pytest.raises(TypeError, match="unknown run options \\['worker'\\]"):
        fig.run(tmp_path, worker=1)


def test_reproduce_all_names_every_figure_that_refuses_an_option():
    figures = [Figure(n, "m:f", without={"retry_failed": "no store"} if n in ("b", "d") else {}) for n in "abcd"]
    with pytest.raises(AmronetError) as info:
        check_options(figures, {"retry_failed": True, "workers": 2})
    assert str(info.value) == ("--retry-failed: b does not take this option (no store), nor does d; reproduce all "
                               "gives every option to every figure, so leave it out or reproduce a, c one by one")
    check_options(figures, {"retry_failed": None, "workers": 2})


@pytest.mark.parametrize("figure", ["fig10", "fig11"])
def test_reproduce_fig10_explorer_is_one_line(figure, tmp_path, capsys):
    out = tmp_path / "x"
    assert main(["reproduce", figure, "--quick", "--explorer", "random", "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err == f"amronet: error: --explorer: {figure} does not take this option (it runs no agents)\n"
    assert not out.exists()


def test_reproduce_all_explorer_is_refused_before_any_figure_runs(tmp_path, capsys):
    assert main(["reproduce", "all", "--quick", "--explorer", "random", "--out", str(tmp_path / "all")]) == 2
    err = capsys.readouterr().err
    assert err == ("amronet: error: --explorer: fig10 does not take this option (it runs no agents), nor does "
                   "fig11, walks; reproduce all gives every option to every figure, so leave it out or reproduce fig5, "
                   "fig7, buildings, failures one by one\n")
    assert not (tmp_path / "all").exists()


def test_reproduce_all_checks_every_figure_before_running_the_first(tmp_path, monkeypatch, seen, capsys):
    _fakes(monkeypatch, retry_failed="it keeps no store")
    assert main(["reproduce", "all", "--out", str(tmp_path), "--retry-failed", "-q"]) == 2
    assert "--retry-failed: f2 does not take this option (it keeps no store)" in capsys.readouterr().err
    assert seen == [] and list(tmp_path.iterdir()) == []
    assert main(["reproduce", "f1", "--out", str(tmp_path / "f1"), "--retry-failed", "-q"]) == 0
    assert seen[0]["options"].retry_failed is True


def test_reproduce_all_runs_every_registered_figure(tmp_path, monkeypatch, seen, capsys):
    _fakes(monkeypatch, explorer="it runs no agents")
    assert main(["reproduce", "all", "--out", str(tmp_path), "--workers", "1", "--time-limit", "7"]) == 0
    assert [(s["figure"], s["out_dir"], s["options"].store) for s in seen] == [
        ("f1", tmp_path / "f1", tmp_path / "f1" / "results.sqlite"),
        ("f2", tmp_path / "f2", tmp_path / "f2" / "results.sqlite")]
    assert {(s["options"].workers, s["options"].time_limit, s["options"].explorer) for s in seen} == \
        {(1, 7.0, "frontier")}
    assert "# f1" in capsys.readouterr().out
    seen.clear()
    assert main(["reproduce", "f2", "--store", str(tmp_path / "s.sqlite"), "-q"]) == 0
    assert seen[0]["options"].store == tmp_path / "s.sqlite" and seen[0]["out_dir"].name == "f2"


def test_reproduce_help_says_the_rule_for_all(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "An option a figure does not take is an error" in text
    assert "With all, every option given goes to every figure" in text


def test_run_jobs_takes_run_options_and_refuses_what_shapes_jobs():
    with pytest.raises(TypeError, match="explorer"):
        run_jobs([], explorer="random")
    assert run_jobs([], RunOptions(workers=1, show_progress=False)) == []


def test_reproduce_paper_runs_the_papers_four_figures_into_out_figure(tmp_path, monkeypatch):
    from amronet.experiments.registry import PAPER, group

    assert group("paper") == ["fig5", "fig7", "fig10", "fig11"] == list(PAPER)
    assert group("all") == list(FIGURES) and group("fig5") is None
    ran = []

    def fake_run(self, out_dir, quick=False, **options):
        ran.append((self.name, Path(out_dir)))
        return {"markdown": f"# {self.name}"}

    monkeypatch.setattr(Figure, "run", fake_run)
    assert main(["reproduce", "paper", "--out", str(tmp_path), "-q"]) == 0
    assert ran == [(name, tmp_path / name) for name in PAPER]
