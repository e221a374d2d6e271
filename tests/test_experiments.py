import csv

import numpy as np
from PIL import Image

from amronet.cli import main
from amronet.experiments.fig5 import run_fig5
from amronet.experiments.options import RunOptions
from amronet.experiments.runner import run_jobs
from amronet.sweeps.stats import mean_ci, mean_ci_columns, mean_ci_text


def test_mean_ci_matches_t_interval():
    mean, half = mean_ci(np.array([1.0, 2.0, 3.0, 4.0]))
    assert mean == 2.5 and abs(half - 2.0540) < 1e-3  # t(0.975, 3) * s / sqrt(4)
    assert mean_ci(np.array([5.0])) == (5.0, 0.0)
    assert np.isnan(mean_ci(np.array([]))[0])


def test_mean_ci_uses_the_same_t_quantile_as_scipy_stats():
    from scipy import stats

    rng = np.random.default_rng(3)
    for n in (2, 3, 5, 13, 50, 51, 280):
        x = rng.normal(size=(n, 4))
        for confidence in (0.9, 0.95, 0.99):
            expected = stats.t.ppf(0.5 + confidence / 2, n - 1) * x[:, 0].std(ddof=1) / np.sqrt(n)
            assert mean_ci(x[:, 0], confidence)[1] == float(expected)  # bit for bit: the figures' tables stay
            columns = stats.t.ppf(0.5 + confidence / 2, n - 1) * x.std(axis=0, ddof=1) / np.sqrt(n)
            assert np.array_equal(mean_ci_columns(x, confidence)[1], columns)


def test_mean_and_ci_are_printed_to_the_half_widths_second_significant_digit():
    assert mean_ci_text(27.0, 4.303) == "27.0 ± 4.3"
    assert mean_ci_text(21.667, 1.434) == "21.7 ± 1.4"
    assert mean_ci_text(2734.0, 143.0) == "2730 ± 140"
    assert mean_ci_text(0.51234, 0.0213) == "0.512 ± 0.021"
    assert mean_ci_text(5.123, 0.0996) == "5.12 ± 0.10"  # 0.0996 rounds up to 0.10: still two digits
    assert mean_ci_text(-3.0, 140.0) == "0 ± 140"  # never "-0"
    assert mean_ci_text(21.6667, 0.0) == "21.67 ± 0"
    assert mean_ci_text(float("nan"), float("nan")) == "n/a"


def test_fig5_and_fig7_tables_count_the_runs_that_reached_the_target():
    from amronet.experiments import fig5, fig7

    entry = {"map": "open-32x32", "r_c": 10.0, "runs": 4, "completed": 3, "ard_mean": 27.0, "ard_ci95": 4.303,
             "ard_est_077": 7.9}
    entry.update({f"{p}_{k}": 8 for p in ("r-strip", "hexagonal", "square", "triangular")
                  for k in ("placed", "estimated")})
    text = fig5._markdown([entry], [])
    assert "| reached target |" in text and "runs done" not in text and "| 3/4 | 27.0 ± 4.3 |" in text
    row = {"bases": 2, "agents_per_base": 1, "runs": 4, "completed": 3, "nodes_mean": 21.667, "nodes_ci95": 1.434,
           "triangle_mean": 0.5}
    text = fig7._markdown([row], [], "office-32x32", 6.0)
    assert "| reached target |" in text and "runs done" not in text and "| 3/4 | 21.7 ± 1.4 | 0.5 |" in text


def test_jobs_are_deterministic_and_ordered():
    sc = {"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"count": 10},
          "sim": {"time_limit": 3.0}}
    jobs = [{"scenario": sc, "seed": s, "labels": {"k": s}} for s in (3, 1, 2)]
    a = run_jobs(jobs, workers=2, show_progress=False)
    b = run_jobs(jobs, workers=1, show_progress=False)
    assert [r["labels"]["k"] for r in a] == [3, 1, 2]
    assert [r["summary"]["coverage"] for r in a] == [r["summary"]["coverage"] for r in b]


def test_meanwhile_runs_once_as_the_first_result_arrives(tmp_path):
    sc = {"map": "open-6x6", "base_stations": [{"x": 0, "y": 0}], "routers": {"count": 5},
          "sim": {"time_limit": 2.0}}
    jobs = [{"scenario": sc, "seed": s} for s in range(3)]
    arrived: list[int] = []
    calls: list[int] = []
    for options in ({"workers": 2}, {"workers": 1}, {"workers": 2, "store": tmp_path / "s.sqlite"}):
        arrived.clear()
        run_jobs(jobs, show_progress=False, on_result=lambda k, _: arrived.append(k),
                 meanwhile=lambda: calls.append(len(arrived)), **options)
        assert calls == [1] and len(arrived) == 3  # once, right after the first result
        calls.clear()
    run_jobs([], workers=1, show_progress=False, meanwhile=lambda: calls.append(0))
    assert calls == [0]  # no result: at the end


def test_fig5_small_writes_runs_table_figure_and_claims(tmp_path):
    report = run_fig5(tmp_path / "f5", maps=("open-32x32",), radii=(10,), agents=(1, 2), starts=1,
                      options=RunOptions(explorer="random", time_limit=2000.0, workers=1, show_progress=False))
    out = tmp_path / "f5"
    rows = list(csv.DictReader((out / "fig5_runs.csv").open()))
    assert len(rows) == 2 and {r["agents"] for r in rows} == {"1", "2"}
    assert all(float(r["agents_connected_fraction"]) == 1.0 for r in rows)
    assert Image.open(out / "fig5.png").size[0] > 400
    text = (out / "fig5_claims.md").read_text()
    assert "RSTR min/est" in text and "| claim (paper) |" in text
    entry = report["table"][0]
    assert entry["r-strip_placed"] >= 1 and entry["hexagonal_estimated"] == 8


def test_fig7_small_via_cli(tmp_path, capsys):
    code = main(["reproduce", "fig7", "--quick", "--explorer", "random", "--time-limit", "300", "--workers", "1",
                 "--out", str(tmp_path / "f7"), "-q"])
    assert code == 0
    rows = list(csv.DictReader((tmp_path / "f7" / "fig7_runs.csv").open()))
    assert len(rows) == 8 and {r["bases"] for r in rows} == {"1", "2"}
    assert (tmp_path / "f7" / "fig7.png").stat().st_size > 10_000


def test_reproduce_bad_explorer_is_one_line(tmp_path, capsys):
    code = main(["reproduce", "fig7", "--quick", "--explorer", "telepathy", "--out", str(tmp_path / "x"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "algorithm.params.explorer" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()
