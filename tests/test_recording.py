"""Tests of amronet.outputs.recording: what a Recorder keeps, the recording.npz format, and its errors."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from numba import njit

from amronet.engine.radio import MEDIA, RadioMedium
from amronet.engine.robots import Role
from amronet.errors import AmronetError
from amronet.outputs.recording import Recorder, Recording, decode_positions, encode_positions, load_recording
from amronet.scenario import load_scenario
from amronet.sim import Simulation


def _run(preset: str, overrides: dict, every: int = 10, full: bool = True, seed: int = 1):
    sim = Simulation(load_scenario(preset, overrides), seed)
    rec = Recorder(every=every, full=full)
    result = sim.run(recorder=rec)
    return sim, rec, result


def _load(blob: bytes) -> Recording:
    with np.load(io.BytesIO(blob)) as data:
        return Recording.from_arrays({k: data[k] for k in data.files})


@pytest.fixture(scope="module")
def spread():
    return _run("self-spreading-6x6", {"sim.time_limit": 20}, every=7)


@pytest.fixture(scope="module")
def agents():
    return _run("agent-assisted-office", {"sim.time_limit": 150}, every=10)


def test_keeps_every_kth_step_and_the_last(spread):
    sim, rec, _ = spread
    assert sim.steps == 200
    assert rec.steps == [*range(0, 200, 7), 200]
    np.testing.assert_allclose(rec.t, np.array(rec.steps) * sim.dt)


def test_round_trip_positions_states_and_links(spread):
    sim, rec, result = spread
    loaded = _load(result.files()["recording.npz"])
    assert loaded.frames == len(rec)
    assert loaded.xy.dtype == np.float32 and loaded.state.dtype == np.uint8
    last = loaded.frames - 1
    # positions on a grid of about a third of a millimetre
    assert loaded.xy_quantum < 1e-3
    np.testing.assert_allclose(loaded.xy[last], sim.swarm.xy, atol=loaded.xy_quantum)
    np.testing.assert_array_equal(loaded.state[last], sim.swarm.state)
    np.testing.assert_array_equal(loaded.status[last], sim.swarm.status)
    np.testing.assert_array_equal(loaded.kind, sim.swarm.role)
    # links are recomputed from positions and r_c (unit disk) and agree with the run's
    np.testing.assert_array_equal(loaded.links(last), sim.table.pairs)
    assert loaded.link_offsets is None
    # the raster coverage of the last frame is the run's
    assert loaded.coverage(last) == pytest.approx(result.summary["coverage"], abs=2e-3)
    assert loaded.meta["r_c"] == sim.scenario.radio.r_c and loaded.meta["every"] == 7
    np.testing.assert_array_equal(loaded.reachable, sim.world.reachable)
    np.testing.assert_array_equal(loaded.omap.cells, sim.world.omap.cells)


def test_status_none_is_stored_as_255_and_read_back_as_minus_one(spread):
    _, _, result = spread
    with np.load(io.BytesIO(result.files()["recording.npz"])) as data:
        assert data["status"].dtype == np.uint8
        assert (data["status"][0] == 255).any()  # routers start without a base station
        assert data["xy_delta"].dtype == np.uint16
        assert json.loads(str(data["meta"]))["format"] == "amronet-recording/1"
    loaded = _load(result.files()["recording.npz"])
    assert loaded.status.min() == -1


def test_growing_swarm_and_agent_trails(agents):
    sim, rec, result = agents
    loaded = _load(result.files()["recording.npz"])
    assert np.all(np.diff(loaded.n) >= 0)
    assert loaded.n[0] < loaded.n[-1] == len(sim.swarm)  # the agents released routers
    last = loaded.frames - 1
    np.testing.assert_allclose(loaded.xy[last, : loaded.n[last]], sim.swarm.xy, atol=loaded.xy_quantum)
    # a router not yet released holds the position where it appears, so its deltas are zero until then
    newest = int(loaded.n[-1]) - 1
    first = int(np.argmax(loaded.n > newest))
    assert first > 0
    np.testing.assert_array_equal(loaded.xy[:first, newest], np.repeat(loaded.xy[first:first + 1, newest], first, 0))
    trails = loaded.trails(last)
    agent_ids = np.flatnonzero(sim.swarm.role == Role.AGENT)
    assert sorted(trails) == agent_ids.tolist()
    assert all(p.shape == (loaded.frames, 2) for p in trails.values())
    live = rec.trails()
    np.testing.assert_allclose(live[int(agent_ids[0])], trails[int(agent_ids[0])], atol=loaded.xy_quantum)


def test_trails_only_recorder_writes_no_recording():
    sim, rec, result = _run("agent-assisted-office", {"sim.time_limit": 20}, full=False)
    assert "recording.npz" not in result.files()
    assert len(rec.trails()) == 3
    with pytest.raises(AmronetError, match="--record"):
        rec.npz_bytes(sim)


def test_recorder_does_not_change_the_run():
    sc = load_scenario("self-spreading-6x6", {"sim.time_limit": 10})
    plain = Simulation(sc, 4).run()
    recorded = Simulation(sc, 4).run(recorder=Recorder(3))
    assert plain.network == recorded.network
    np.testing.assert_array_equal(plain.timeseries["coverage"], recorded.timeseries["coverage"])


def test_encode_decode_wraps_modulo_2_16():
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 50, size=(30, 40, 2))
    quantum = 50 / 65535
    delta = encode_positions(xy, np.zeros(2), quantum)
    assert delta.dtype == np.uint16
    np.testing.assert_allclose(decode_positions(delta, np.zeros(2), quantum), xy, atol=quantum)


@njit(cache=True)
def _half_range_margin(xa, ya, xb, yb, d, sa, sb, floor_db, h):
    """A toy radio heard within half of ``r_c`` only (10 dB per ``r_c``)."""
    return 10.0 * (0.5 * h.r_c - d) / h.r_c


@MEDIA.register("test-recording-medium")
class _HalfRange(RadioMedium):
    """A medium whose links are not the unit-disk graph: pairs within half of ``r_c`` only."""

    link_margin = _half_range_margin


def test_other_media_store_their_links():
    sim, _, result = _run("self-spreading-6x6", {"sim.time_limit": 5, "radio.model": "test-recording-medium"},
                          every=5)
    loaded = _load(result.files()["recording.npz"])
    assert loaded.link_offsets is not None and len(loaded.link_offsets) == loaded.frames + 1
    np.testing.assert_array_equal(loaded.links(loaded.frames - 1), sim.table.pairs)
    xy = loaded.frame(0)["xy"]
    pairs = loaded.links(0)
    gap = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1)
    assert len(pairs) and gap.max() < 0.51 * loaded.r_c  # the medium's links (positions are quantised)
    near = np.linalg.norm(xy[:, None] - xy[None], axis=2)
    assert np.count_nonzero(np.triu(near < loaded.r_c, 1)) > len(pairs)


def test_errors_name_the_problem(tmp_path):
    with pytest.raises(AmronetError, match=r"has no recording\.npz: run it again with --record"):
        load_recording(tmp_path)
    with pytest.raises(AmronetError, match="does not exist"):
        load_recording(tmp_path / "missing.npz")
    bad = tmp_path / "bad" / "recording.npz"
    bad.parent.mkdir()
    bad.write_text("not a zip")
    with pytest.raises(AmronetError, match="is not a recording"):
        load_recording(bad.parent)
    np.savez_compressed(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(AmronetError, match="'meta' is missing"):
        load_recording(tmp_path / "other.npz")
    for every in (0, -3, 1.5):
        with pytest.raises(AmronetError, match="--record-every"):
            Recorder(every=every)


def test_a_damaged_recording_names_the_file_and_what_is_wrong(spread):
    sim, rec, _ = spread
    arrays = rec.arrays(sim)
    cases = [
        ({"meta": np.array("{oops")}, r"rec\.npz is damaged or was not written by amronet run --record \(its meta "
                                      r"is not valid JSON\); record the run again"),
        ({"meta": np.array("3")}, r"its meta is a JSON int, not an object"),
        ({"meta": np.array(json.dumps({"format": "amronet-recording/1", "algorithm": "x", "map": "m", "seed": 1}))},
         r"its meta lacks 'r_c'"),
        ({"meta": np.array(json.dumps({**json.loads(str(arrays["meta"])), "r_c": "wide"}))},
         r"is damaged .*\(its meta's r_c 'wide' is not a range in metres in \(0, 100000\]\)"),
        ({"xy_quantum": np.zeros(3)},
         r"is damaged .*\(array 'xy_quantum' has shape \(3,\), not \(\) \(a single number\)\)"),
        ({"state": np.zeros(3, np.uint8)}, r"array 'state' has shape \(3,\), not \(\d+, \d+\) \(frames x robots\)"),
    ]
    for change, message in cases:
        with pytest.raises(AmronetError, match=message):
            Recording.from_arrays({**arrays, **change}, where="rec.npz")
