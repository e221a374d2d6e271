"""A run's result and its files (amronet.sim.results)."""

import json

import numpy as np
import pytest

import amronet
from amronet.engine.robots import Role
from amronet.outputs.files import MANIFEST
from amronet.viz.run_snapshot import run_snapshot_png


@pytest.fixture(scope="module")
def result():
    return amronet.run("self-spreading-obstacles-6x6", seed=2, overrides={"sim.time_limit": 4})


@pytest.fixture(scope="module")
def agent_result():
    return amronet.run("agent-assisted-office", seed=1, overrides={"sim.time_limit": 3})


def test_the_summary_counts_what_the_run_holds(result):
    s, sw = result.summary, result.run.swarm
    routers = sw.role == Role.ROUTER
    assert s["routers_total"] == int(routers.sum()) == 30
    assert s["nodes_total"] == s["routers_deployed"] + 1
    assert sum(s["states"].values()) == len(sw)
    assert s["agents"] == 0 and s["agents_connected_fraction"] is None and s["agents_connected_min"] is None
    assert 0.0 <= s["connected_coverage"] <= s["coverage"] <= 1.0
    assert s["mean_distance_per_router_m"] == pytest.approx(float(sw.distance[routers].mean()))


def test_the_network_lists_every_node_where_it_is(result):
    nodes = result.network["nodes"]
    assert [n["id"] for n in nodes] == list(range(len(nodes)))
    xy = np.array([[n["x"], n["y"]] for n in nodes])
    np.testing.assert_array_equal(xy, result.run.swarm.xy)
    assert {n["kind"] for n in nodes} == {"base", "router"}


def test_timeseries_csv_has_one_line_per_record(result):
    lines = result.timeseries_csv().splitlines()
    assert lines[0] == "t,coverage,connected_coverage,routers_deployed,components"
    assert len(lines) == len(result.timeseries["t"]) + 1
    t, cov, *_ = lines[-1].split(",")
    assert float(t) == pytest.approx(4.0) and float(cov) == pytest.approx(result.timeseries["coverage"][-1], abs=1e-6)


def test_runs_with_agents_add_the_agents_connected_column(agent_result):
    ts = agent_result.timeseries
    assert "agents_connected" in ts and ((ts["agents_connected"] >= 0) & (ts["agents_connected"] <= 1)).all()
    assert agent_result.timeseries_csv().splitlines()[0].endswith(",agents_connected")
    assert agent_result.summary["agents_connected_min"] <= agent_result.summary["agents_connected_fraction"]


def test_files_and_save(result, tmp_path):
    files = result.files(snapshot=run_snapshot_png(result))
    assert sorted(files) == ["network.json", "snapshot.png", "summary.json", "timeseries.csv"]
    assert files["snapshot.png"].startswith(b"\x89PNG\r\n\x1a\n")
    assert json.loads(files["summary.json"]) == json.loads(json.dumps(result.summary))
    assert "snapshot.png" not in result.files()
    out = result.save(tmp_path / "r")
    assert sorted(p.name for p in out.iterdir()) == sorted([MANIFEST, "network.json", "summary.json",
                                                            "timeseries.csv"])
