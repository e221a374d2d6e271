"""What ``amronet run`` prints (amronet.outputs.console), and the ``wrote FOLDER/:`` lines of every command."""

from __future__ import annotations

import copy

import pytest

from amronet.cli import main
from amronet.outputs.console import folder_name, run_lines, wrote_line

PLAIN = {
    "algorithm": "self-spreading", "map": "open-6x6", "seed": 3, "r_c": 1.0, "stop_reason": "settled",
    "sim_time_s": 120.5, "wall_time_s": 0.42, "nodes_total": 31, "routers_deployed": 30, "routers_total": 30,
    "states": {"base": 1, "reference": 30}, "coverage": 0.9856, "connected_coverage": 0.9801,
    "reachable_area_m2": 36.0, "coverage_method": "raster", "agents": 0, "mission": None,
    "scenario": {"radio": {"model": "unit-disk"}},
}
MISSION = {
    "connected_fraction": 0.68, "longest_outage_s": 1809.6, "outages": 60, "time_all_connected_fraction": 0.229,
    "relays_used": 15, "relays_per_100m2_covered": 4.23, "distance_travelled_m": 5400.0,
    "drop_rule": "last-reference",
    "per_agent": [{"id": 1, "connected_fraction": 1.0}, {"id": 2, "connected_fraction": 0.091},
                  {"id": 3, "connected_fraction": 0.95}],
}


def _event(t, nodes, restored, kind="routers"):
    return {"t": t, "kind": kind, "nodes": nodes, "coverage_before": 0.5, "coverage_after": 0.45,
            "connected_coverage_before": 0.139, "connected_coverage_after": 0.075, "restored_after_s": restored}


def _agent_run(**faults):
    s = copy.deepcopy(PLAIN)
    s.update(algorithm="agent-assisted", agents=3, mission=copy.deepcopy(MISSION),
             scenario={"radio": {"model": "multi-wall"}})
    if faults:
        s["faults"] = faults
    return s


def _labelled(lines):
    return {line[2:12].strip(): line[12:] for line in lines[1:]}


def test_a_plain_run_prints_headline_nodes_and_coverage_only():
    lines = run_lines(PLAIN)
    assert lines[0].startswith("self-spreading on open-6x6 (seed 3, r_c = 1 m): settled after 120.5 s simulated")
    assert list(_labelled(lines)) == ["nodes", "coverage"]
    assert _labelled(lines)["coverage"].startswith("98.56 %, connected 98.01 % of 36.0 m² reachable")


def test_an_agent_run_prints_time_connected_longest_outage_and_relays():
    lines = run_lines(_agent_run())
    assert "multi-wall radio" in lines[0]
    got = _labelled(lines)
    assert list(got) == ["nodes", "coverage", "agents", "outages", "relays"]
    assert got["agents"] == "3: connected 68.0 % of the time on average, worst 9.1 %, all at once 22.9 %"
    assert got["outages"] == "60, longest 1809.6 s"
    assert got["relays"] == "15 used, 4.2 per 100 m² covered"
    assert all(len(line) <= 100 for line in lines[1:])  # short lines after the headline


def test_an_agent_never_cut_off_has_no_outages():
    s = _agent_run()
    s["mission"].update(outages=0, longest_outage_s=0.0, per_agent=[{"id": 1, "connected_fraction": 1.0}],
                        connected_fraction=1.0)
    got = _labelled(run_lines(s))
    assert got["outages"] == "none" and got["agents"] == "1: connected 100.0 % of the time"


def test_faults_print_each_event_and_what_the_repair_cost():
    s = _agent_run(nodes_failed=3, events=[_event(300.0, [4], 25.5), _event(420.0, [7, 9], None)],
                   extra_routers=4, repair_distance_m=4.88, routers_moved=1)
    lines = run_lines(s)
    k = next(i for i, line in enumerate(lines) if line.startswith("  faults"))
    assert lines[k] == "  faults    t = 300 s: 1 router failed, connected 13.9 → 7.5 %, restored after 25.5 s"
    assert lines[k + 1] == "            t = 420 s: 2 routers failed, connected 13.9 → 7.5 %, not restored"
    assert lines[k + 2] == "  repair    1 router moved (4.9 m in all), 4 routers added after the first fault"


def test_many_fault_events_are_summed_up_and_named_nodes_and_bases_are_said():
    events = [_event(10.0, [0], 0.0, kind="base_station"), _event(20.0, [4, 17], 2.0, kind="ids")]
    events += [_event(30.0 + k, [20 + k], None if k % 2 else 1.0, kind="rate_per_hour") for k in range(5)]
    s = _agent_run(nodes_failed=9, events=events, extra_routers=0, repair_distance_m=0.0, routers_moved=0,
                   skipped=["faults[1]: nodes [99] did not exist, were agents or had failed at t = 20 s"])
    text = "\n".join(run_lines(s))
    assert "t = 10 s: base station (node 0) failed" in text and "t = 20 s: nodes 4, 17 failed" in text
    assert "... 4 more events until t = 34 s: 4 nodes failed, 2 of 4 restored" in text
    assert "skipped: faults[1]: nodes [99]" in text and "0 routers moved (0.0 m in all)" in text


def test_faults_that_never_struck_say_so():
    got = _labelled(run_lines({**PLAIN, "faults": {"nodes_failed": 0, "events": []}}))
    assert got["faults"] == "none struck before the run ended" and "repair" not in got


@pytest.mark.parametrize("out", ["runs/a", "runs/a/", "runs//a//"])
def test_a_folder_is_named_with_one_slash(out):
    assert folder_name(out) == "runs/a/"
    assert wrote_line(out, ["summary.json", "timeseries.csv"]) == "  wrote     runs/a/: summary.json timeseries.csv"


def test_run_with_faults_prints_them_and_names_its_folder_once(tmp_path, capsys):
    out = f"{tmp_path / 'r'}/"
    code = main(["run", "--preset", "self-spreading-6x6", "--seed", "2", "--out", out, "--no-snapshot",
                 "--set", "sim.time_limit=40", "--set", "faults=[{at: 30, routers: 0.5}]"])
    assert code == 0
    text = capsys.readouterr().out
    assert "\n  faults    t = 30 s: " in text and "\n  repair    " in text
    assert f"wrote     {tmp_path / 'r'}/: summary.json" in text and "//" not in text


def test_plan_and_export_name_their_folder_once(tmp_path, capsys):
    store = tmp_path / "s.sqlite"
    assert main(["plan", "--map", "office-32x32", "--base", "1,1", "--rc", "8", "--agents", "1", "--runs", "1",
                 "--workers", "1", "--store", str(store), "--out", f"{tmp_path / 'plan'}/"]) == 0
    assert f"wrote {tmp_path / 'plan'}/: plan.json plan.md" in capsys.readouterr().out
    assert main(["results", str(store), "--export", "csv", "--out", f"{tmp_path / 'csv'}/"]) == 0
    assert capsys.readouterr().out.startswith(f"wrote {tmp_path / 'csv'}/: runs.csv")
