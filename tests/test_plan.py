import json
import math

import pytest
from PIL import Image

from amronet.cli import main
from amronet.errors import AmronetError
from amronet.experiments.options import RunOptions
from amronet.planning import Mission, plan, write_plan
from amronet.sweeps import ResultStore


@pytest.fixture(scope="module")
def office_plan():
    return plan("office-32x32", [(1.0, 1.0)], r_c=8.0, agents_per_base=2, runs=5, options=RunOptions(workers=2))


def test_plan_has_estimate_patterns_distribution_and_recommendation(office_plan):
    p = office_plan
    assert 900 < p.area_m2 <= 1024
    assert p.estimate_nodes == math.ceil(0.77 * p.area_m2 / 64 - 1e-9)
    assert set(p.patterns) == {"r-strip", "hexagonal", "square", "triangular"}
    assert all(v["placed"] >= 1 for v in p.patterns.values())
    d = p.distribution
    assert d["runs"] == 5 and d["completed"] == 5
    values = sorted(r["routers_deployed"] for r in p.runs)
    assert d["min"] == values[0] and d["max"] == values[-1] and d["median"] == values[2]
    assert values[-2] <= p.recommended <= values[-1]  # the 95th percentile of 5, rounded up
    assert p.typical_seed in [r["seed"] for r in p.runs if abs(r["routers_deployed"] - d["median"]) ==
                              min(abs(v - d["median"]) for v in values)]
    assert all(r["agents_connected_min"] == 1.0 for r in p.runs)


def test_confidence_changes_the_recommendation(office_plan):
    low = plan("office-32x32", [(1.0, 1.0)], r_c=8.0, agents_per_base=2, runs=5, confidence=0.5,
               options=RunOptions(workers=1))
    assert low.recommended == math.ceil(office_plan.distribution["median"])
    assert low.runs == office_plan.runs  # same seeds, same runs


def test_plan_writes_json_markdown_and_a_typical_picture(office_plan, tmp_path):
    out = write_plan(office_plan, tmp_path / "plan")
    doc = json.loads((out / "plan.json").read_text())
    assert doc["recommended_routers"] == office_plan.recommended
    assert doc["estimate_077"]["routers_to_carry"] == office_plan.estimate_nodes - 1
    md = (out / "plan.md").read_text()
    assert f"Carry {office_plan.recommended} routers" in md and "typical.png" in md
    assert Image.open(out / "typical.png").size[0] > 400


def test_plan_cli_json_with_a_store(tmp_path, capsys):
    store = tmp_path / "plan.sqlite"
    args = ["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "8", "--agents", "1", "--runs", "3",
            "--workers", "1", "--store", str(store), "--json"]
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["agent_assisted"]["distribution"]["runs"] == 3 and doc["recommended_routers"] >= 1
    with ResultStore(store) as st:
        assert len(st.runs()) == 3 and st.sweeps()[0]["name"].startswith("plan-office-32x32")
    assert main(args) == 0  # the runs come from the store
    assert json.loads(capsys.readouterr().out)["agent_assisted"] == doc["agent_assisted"]


@pytest.mark.parametrize(("args", "option"), [
    (["--base", "0.02,0.02"], "--base"),  # inside the office's outer wall
    (["--base", "40,1"], "--base"),  # outside the map
    (["--base", "1,1", "--runs", "0"], "--runs"),
    (["--base", "1,1", "--confidence", "1.5"], "--confidence"),
    (["--base", "1,1", "--agents", "0"], "--agents"),
    (["--base", "x"], "--base"),
    ([], "--base"),
])
def test_plan_bad_input_is_one_line(tmp_path, capsys, args, option):
    assert main(["plan", "--map", "office-32x32", "--rc", "8", "--runs", "2", "--workers", "1", "--out",
                 str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"amronet: error: {option}") and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_plan_unknown_map_and_bad_radius():
    with pytest.raises(AmronetError, match="unknown map"):
        plan("no-such-map", [(1.0, 1.0)], r_c=8.0, agents_per_base=1, runs=1)
    with pytest.raises(AmronetError, match="--rc"):
        plan("office-32x32", [(1.0, 1.0)], r_c=-1.0, agents_per_base=1, runs=1)


def _fail_one_run(store):
    from amronet import __version__

    with ResultStore(store) as st:
        run = st.runs()[0]
        h, seed = run["scenario_hash"], run["seed"]
        scenario = st.load(h, seed)["summary"]["scenario"]
        st.record(h, seed, scenario, {"status": "failed", "error": "boom", "summary": None, "timeseries": None,
                                      "wall_time_s": 0.0, "host": "test", "amronet_version": __version__})
    return seed


def test_plan_retries_failed_runs_only_with_retry_failed(tmp_path, capsys):
    store = tmp_path / "plan.sqlite"
    args = ["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "8", "--agents", "1", "--runs", "2",
            "--workers", "1", "--store", str(store), "--json"]
    assert main(args) == 0
    first = json.loads(capsys.readouterr().out)["agent_assisted"]["runs"]
    seed = _fail_one_run(store)
    assert main(args) == 0
    runs = json.loads(capsys.readouterr().out)["agent_assisted"]["runs"]
    assert [r["status"] for r in runs if r["seed"] == seed] == ["failed"]
    p = plan("office-32x32", [(1.0, 1.0)], r_c=8.0, agents_per_base=1, runs=2,
             options=RunOptions(workers=1, store=store))
    assert any("1 of 2 runs failed (--retry-failed runs them again): boom" in w for w in p.warnings)
    assert main([*args, "--retry-failed"]) == 0
    assert json.loads(capsys.readouterr().out)["agent_assisted"]["runs"] == first


def test_plan_json_gives_the_picture_only_with_out(tmp_path, capsys):
    args = ["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "8", "--agents", "1", "--runs", "1",
            "--workers", "1", "--json"]
    assert main(args) == 0
    assert json.loads(capsys.readouterr().out)["picture"] is None
    assert main([*args, "--out", str(tmp_path / "plan")]) == 0
    picture = json.loads(capsys.readouterr().out)["picture"]
    assert picture == str(tmp_path / "plan" / "typical.png") and Image.open(picture).size[0] > 400


def test_plan_help_says_the_picture_needs_out(capsys):
    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "the picture is written only with --out" in text and "--retry-failed" in text


def test_plan_with_radio_drop_rule_and_stock_reports_time_connected_and_warns(tmp_path, capsys):
    """Issue #19: a short stock under walls leaves agents cut off, and the plan says so."""
    p = plan("office-32x32", [(1.0, 1.0)], r_c=6.0, agents_per_base=2, runs=3,
             options=RunOptions(workers=1, show_progress=False, time_limit=300.0),
             mission=Mission(radio={"model": "multi-wall"}, drop_rule="link-quality", stock=2))
    sc = p.scenario
    assert sc["radio"]["model"] == "multi-wall" and sc["algorithm"]["params"]["drop_rule"] == "link-quality"
    assert sc["agents"]["routers_carried"] == 2 and sc["agents"]["when_empty"] == "continue"
    c = p.connected
    assert c["runs"] == 3 and c["cut_off_runs"] >= 1 and 0.0 <= c["min"] <= c["median"] <= c["max"] <= 1.0
    assert any("cut off" in w for w in p.warnings) and any("stock ran out" in w for w in p.warnings)
    assert all(r["relays_used"] <= 2 * 2 for r in p.runs)
    assert "Time the agents were connected" in p.markdown(picture=None) and "drop rule link-quality" in p.markdown()
    assert json.loads(json.dumps(p.to_dict()))["connected"]["runs"] == 3


@pytest.mark.parametrize(("args", "option"), [
    (["--radio", "telepathy"], "--radio"),
    (["--drop-rule", "nearest"], "--drop-rule"),
    (["--drop-rule", "radius", "--drop", "radius=-1"], "--drop"),
    (["--stock", "-1"], "--stock"),
])
def test_plan_bad_mission_options_are_one_line(tmp_path, capsys, args, option):
    code = main(["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "6", "--runs", "1", "--out",
                 str(tmp_path / "p"), *args])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and option in err
    assert not (tmp_path / "p").exists()


PATHS_CSV = "t,agent,x,y\n0,0,1.5,1.5\n40,0,1,20\n0,1,1.5,1.5\n60,1,25,3\n"


def test_plan_of_a_replayed_mission_counts_every_run_that_followed_the_paths(tmp_path):
    """Issue #15: a team replays its paths and asks how many routers they need."""
    paths = tmp_path / "paths.csv"
    paths.write_text(PATHS_CSV)
    p = plan("office-32x32", [(1.0, 1.0)], r_c=6.0, agents_per_base=2, runs=2,
             options=RunOptions(workers=1, show_progress=False), mission=Mission(trajectories=paths))
    assert p.scenario["agents"]["trajectories"] == str(paths.resolve())
    assert all(r["stop_reason"] == "settled" for r in p.runs)  # a replay ends where its paths end
    assert p.distribution["completed"] == 2 and p.recommended is not None and p.recommended >= 1
    assert not any("did not reach" in w for w in p.warnings)
    assert "that followed the paths of" in p.markdown(picture=None)


@pytest.mark.parametrize(("content", "what"), [
    ("t,agent,x,y\n0,7,1.5,1.5\n", "unknown agent 7"),
    (None, "no file"),
])
def test_plan_bad_trajectories_are_one_line_naming_the_option(tmp_path, capsys, content, what):
    paths = tmp_path / "paths.csv"
    if content is not None:
        paths.write_text(content)
    code = main(["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "6", "--runs", "1", "--out",
                 str(tmp_path / "p"), "--trajectories", str(paths)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "--trajectories" in err and what in err
    assert not (tmp_path / "p").exists()


@pytest.mark.parametrize(("args", "words"), [
    (["--drop", "novalue"], "--drop: expected KEY=VALUE, got 'novalue'; the last-reference rule takes no keys; the "
                            "rules that take some: distance-junction, link-quality, radius, strip-goals (--drop-rule)"),
    (["--drop-rule", "link-quality", "--drop", "=3"],
     "--drop: expected KEY=VALUE, got '=3'; the link-quality rule takes: drop_margin_db, loss_margin_db, smoothing_s"),
    (["--drop-rule", "radius", "--drop", "radius=[1"], "--drop: radius: value '[1' is not valid YAML at line 1"),
])
def test_plan_drop_errors_name_drop_and_its_keys(tmp_path, capsys, args, words):
    """Issue #45 (5d): the error names --drop (not --set) and the keys the drop rule takes."""
    code = main(["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "6", "--runs", "1", "--out",
                 str(tmp_path / "p"), *args])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith(f"amronet: error: {words}"), err
    assert not (tmp_path / "p").exists()


@pytest.mark.parametrize(("args", "words"), [
    (["--rc", "1"], "--rc: 1 m leaves the agents an 'about to lose' band (5 % of r_c) no wider than one of their "
                    "steps (0.125 m); give --rc above 2.5 m"),
    (["--rc", "2.5"], "--rc: 2.5 m leaves the agents an 'about to lose' band (5 % of r_c) no wider than one of "
                      "their steps (0.125 m); give --rc above 2.5 m"),
    (["--rc", "6", "--time-limit", "1e8"], "--time-limit: 1e+08 s is more than 10,000,000 steps of 0.25 s per run; "
                                           "lower --time-limit"),
])
def test_plan_advice_names_plan_s_own_options(tmp_path, capsys, args, words):
    """Issue #45 (5e): not loss_margin, sim.dt or --force, which plan does not have."""
    code = main(["plan", "--map", "office-32x32", "--base", "1,1", "--runs", "1", "--out", str(tmp_path / "p"),
                 *args])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith(f"amronet: error: {words}"), err
    for foreign in ("loss_margin", "sim.dt", "--force", "sim.time_limit"):
        assert foreign not in err
    assert not (tmp_path / "p").exists()


@pytest.mark.parametrize(("args", "words"), [
    (["--radio", "multi-wall"], "--optimum: 4585 reachable cells can never be covered on the 3 m lattice"),
    (["--optimum", "1e9"], "--optimum: must be a number of seconds > 0 and at most")])
def test_plan_optimum_errors_come_before_the_runs_and_name_optimum(args, words, tmp_path, capsys, monkeypatch):
    """An optimum that cannot be solved is refused before any run (none is lost); plan has no --spacing."""

    def no_runs(*args, **kwargs):
        raise AssertionError("the runs started before the optimum was checked")

    monkeypatch.setattr("amronet.planning.plan", no_runs)
    code = main(["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "6", "--runs", "1", "--optimum", "5", "-q",
                 "--out", str(tmp_path / "p"), *args])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert err.startswith(f"amronet: error: {words}"), err
    assert ("amronet optimum --spacing" in err) == ("multi-wall" in args) and not (tmp_path / "p").exists()


def test_plan_optimum_is_0_routers_when_the_base_covers_everything(capsys):
    code = main(["plan", "--map", "open-6x6", "--base", "0,0", "--rc", "50", "--runs", "1", "--optimum", "5", "--json"])
    optimum = json.loads(capsys.readouterr().out)["optimum"]
    assert code == 0 and (optimum["routers"], optimum["lower_bound"], optimum["optimal"]) == (0, 0, True)
    assert optimum["spacing_m"] == 25.0
