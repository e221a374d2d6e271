import csv

import numpy as np
from PIL import Image

from amronet.experiments.fig10 import ALGORITHMS, _hold, _time_to_fraction, run_coverage_over_time
from amronet.experiments.options import RunOptions


def _options(time_limit: float, baselines: bool | None = None) -> RunOptions:
    return RunOptions(time_limit=time_limit, workers=1, show_progress=False, baselines=baselines)


def test_hold_carries_the_last_value_past_the_end():
    t = np.array([0.0, 1.0, 2.0])
    v = np.array([0.1, 0.5, 0.7])
    np.testing.assert_allclose(_hold(t, v, np.array([0.0, 0.5, 1.0, 2.0, 5.0])), [0.1, 0.1, 0.5, 0.7, 0.7])
    assert _time_to_fraction(t, v, 0.9) == 2.0
    assert _time_to_fraction(t, np.array([0.1, 0.95, 1.0]), 0.9) == 1.0


def test_fig10_and_fig11_small(tmp_path):
    f10 = run_coverage_over_time("fig10", tmp_path / "fig10", runs=2, options=_options(20.0, baselines=True))
    out = tmp_path / "fig10"
    rows = list(csv.DictReader((out / "fig10_runs.csv").open()))
    assert len(rows) == 12 and {r["algorithm"] for r in rows} == {"self-spreading", "dssa", "potential-field", "vor",
                                                                  "minimax", "lloyd"}
    # paired comparison: run k of every algorithm starts from the same seed
    assert {(r["run"], r["seed"]) for r in rows} == {("0", "0"), ("1", "1")}
    ts = list(csv.DictReader((out / "fig10_timeseries.csv").open()))
    assert {r["algorithm"] for r in ts} == set(ALGORITHMS)
    assert all(0.0 <= float(r["connected_coverage"]) <= float(r["coverage"]) + 1e-9 <= 1.0 + 1e-9 for r in ts)
    for algorithm, curves in f10["curves"].items():
        assert curves["coverage"].shape == (2, 21), algorithm
        assert curves["coverage"][:, -1].mean() > curves["coverage"][:, 0].mean()  # everybody spreads
    text = (out / "fig10_claims.md").read_text()
    assert "| claim (paper) |" in text and "slightly lower" in text
    assert "| VOR (location-aware) |" in text  # an extra line of the table, not a party to the paper's claims
    assert all("VOR" not in c.ours and "Lloyd" not in c.ours for c in f10["claims"])
    # self-spreading never disconnects a router: both of its runs count as connected, DSSA's (spread apart) not
    by_algorithm = {e["algorithm"]: e for e in f10["table"]}
    assert by_algorithm["self-spreading"]["runs_all_connected"] == 2
    assert by_algorithm["dssa"]["runs_all_connected"] < 2
    assert Image.open(out / "fig10.png").size[0] > 800

    # Fig. 11 finds the Fig. 10 table next to it and compares final coverage
    f11 = run_coverage_over_time("fig11", tmp_path / "fig11", runs=2, options=_options(20.0))
    claims = {c.claim: c for c in f11["claims"]}
    assert "almost the same" in " ".join(c.paper for c in claims.values())
    assert all("not evaluated" not in c.verdict for c in claims.values())
    mismatched = run_coverage_over_time("fig11", tmp_path / "fig11", runs=2, options=_options(10.0))
    verdicts = [c.verdict for c in mismatched["claims"]]
    assert any("not evaluated" in v for v in verdicts)
    assert any("20 s" in c.ours and "10 s" in c.ours for c in mismatched["claims"])
    alone = run_coverage_over_time("fig11", tmp_path / "elsewhere" / "x", runs=1, options=_options(5.0),
                                   algorithms=("self-spreading", "dssa"))
    assert any("not evaluated" in c.verdict for c in alone["claims"])


def test_reproduce_fig10_quick_on_a_dask_local_cluster_resumes_from_the_store(tmp_path, capsys):
    from amronet.cli import main

    out = tmp_path / "fig10"
    args = ["reproduce", "fig10", "--quick", "--out", str(out), "-q"]
    assert main([*args, "--cluster", "local", "--workers", "1"]) == 0
    first = (out / "fig10_runs.csv").read_text()
    assert (out / "results.sqlite").is_file() and len(first.splitlines()) == 7
    # again on the local pool: every run comes from the store, the table is the same
    assert main([*args, "--workers", "1"]) == 0
    again = (out / "fig10_runs.csv").read_text()
    strip = [line.rsplit(",", 1)[0] for line in first.splitlines()]  # wall time is the last column
    assert [line.rsplit(",", 1)[0] for line in again.splitlines()] == strip


def test_reproduce_retries_failed_runs_only_with_retry_failed(tmp_path, capsys):
    import sqlite3

    from amronet.cli import main

    out = tmp_path / "fig10"
    args = ["reproduce", "fig10", "--quick", "--out", str(out), "-q", "--workers", "1"]
    assert main(args) == 0
    with sqlite3.connect(out / "results.sqlite") as db:  # as if one run had crashed
        db.execute("UPDATE runs SET status = 'failed', error = 'boom' WHERE (scenario_hash, seed) = "
                   "(SELECT scenario_hash, seed FROM runs ORDER BY seed LIMIT 1)")
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--retry-failed" in err and "boom" in err
    assert main([*args, "--retry-failed"]) == 0
    with sqlite3.connect(out / "results.sqlite") as db:
        assert db.execute("SELECT count(*) FROM runs WHERE status != 'done'").fetchone() == (0,)


def test_outputs_get_the_usual_permissions(tmp_path):
    import stat

    from amronet.outputs.files import write_file_atomically, write_files_atomically

    def mode(path):
        return stat.S_IMODE(path.stat().st_mode)

    (tmp_path / "plain").mkdir()
    (tmp_path / "plain.txt").write_bytes(b"z")
    write_files_atomically(tmp_path / "out", {"a.txt": b"x"})
    write_file_atomically(tmp_path / "b.txt", lambda p: p.write_bytes(b"y"))
    assert mode(tmp_path / "out") == mode(tmp_path / "plain")
    assert mode(tmp_path / "out" / "a.txt") == mode(tmp_path / "plain.txt")
    assert mode(tmp_path / "b.txt") == mode(tmp_path / "plain.txt")
    assert mode(tmp_path / "b.txt") & stat.S_IRGRP  # not private (under the usual umask 022)


def test_bad_seed_and_workers_are_one_line_errors(tmp_path, capsys):
    from amronet.cli import main

    assert main(["run", "--preset", "dssa-6x6", "--seed", "-1", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("amronet: error: seed:") and len(err.strip().splitlines()) == 1
    assert main(["reproduce", "fig10", "--quick", "--workers", "0", "--out", str(tmp_path / "f"), "-q"]) == 2
    assert "--workers" in capsys.readouterr().err
    assert not (tmp_path / "r").exists() and not (tmp_path / "f").exists()


def test_the_paper_figures_run_the_papers_algorithms_unless_asked_for_the_baselines(tmp_path, capsys):
    """``reproduce fig10`` stays the paper's three (a minute for the paper); ``--baselines`` adds the Voronoi ones."""
    from amronet.cli.main import main

    assert main(["reproduce", "fig10", "--quick", "--out", str(tmp_path / "plain"), "--workers", "1", "--quiet"]) == 0
    plain = {r["algorithm"] for r in csv.DictReader((tmp_path / "plain" / "fig10_runs.csv").open())}
    assert plain == {"self-spreading", "dssa", "potential-field"}
    assert main(["reproduce", "fig10", "--quick", "--baselines", "--out", str(tmp_path / "more"), "--workers", "1",
                 "--quiet"]) == 0
    more = {r["algorithm"] for r in csv.DictReader((tmp_path / "more" / "fig10_runs.csv").open())}
    assert more == plain | {"vor", "minimax", "lloyd"}
    capsys.readouterr()
    assert main(["reproduce", "fig7", "--baselines", "--out", str(tmp_path / "f7")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "amronet: error: --baselines: fig7 does not take this option (only fig10 and fig11 draw the " \
                  "Voronoi baselines)"
    assert not (tmp_path / "f7").exists()
