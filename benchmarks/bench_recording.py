"""Size and cost of ``amronet run --record`` for 3 000 robots over 10 000 steps (README: Pictures, recordings).

The swarm is the one of ``amronet bench`` (the ``hospital_section`` floor plan scaled until every robot has
0.25 m², routers scattered over it, one base station per 1 000 robots, r_c = 1 m, self-spreading). The loop runs
the full step and shows the recorder every step, as ``Simulation.run`` does; a frame is kept every ``--every``
steps. Reported: the size of ``recording.npz``, bytes per robot and frame, the time the recorder takes per kept
frame and in total against the stepping time, and the time to encode and to load the file.

With ``--replay`` it also writes the replay page of that recording and measures, in a headless Chromium
(``/usr/bin/chromium`` driven by Playwright), the page's load time and the time to draw one frame with every
layer on (``performance.now()`` around the page's draw and until its pixels exist), and the frame rate while
playing at 16x.

Run: ``.venv/bin/python benchmarks/bench_recording.py [--robots 3000 --steps 10000 --every 10] [--replay] [--json]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import json
import math
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from amronet.outputs.recording import Recorder, Recording
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.bench import _largest_free_region
from amronet.world.builtin import resolve_map


def bench_simulation(robots: int, map_name: str = "hospital_section", seed: int = 0) -> Simulation:
    """The swarm of ``amronet bench``: a scaled real floor plan, routers scattered over it."""
    omap = resolve_map(map_name)
    rng = np.random.default_rng(seed)
    largest = _largest_free_region(omap)
    area = np.count_nonzero(largest) * omap.resolution**2
    scale = max(1.0, math.sqrt(robots * 0.25 / area))
    omap = dataclasses.replace(omap, resolution=omap.resolution * scale, _cache={})
    rows, cols = np.nonzero(largest)
    pick = rng.choice(len(rows), size=max(1, robots // 1000), replace=False)
    bases = omap.cell_centres(rows[pick], cols[pick])
    scenario = load_scenario({
        "name": f"bench-recording-{robots}",
        "map": map_name,
        "algorithm": {"name": "self-spreading"},
        "radio": {"r_c": 1.0},
        "base_stations": [{"x": float(x), "y": float(y)} for x, y in bases],
        "routers": {"count": robots, "start": "uniform"},
        "sim": {"time_limit": 1e9, "stop_when_settled": False},
    })
    return Simulation(scenario, seed, omap=omap, force=True)  # a long time limit, stopped by the benchmark


CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def replay_timing(rec: Recording) -> dict:
    """Write the replay page of ``rec`` and time it in headless Chromium."""
    from playwright.sync_api import sync_playwright

    from amronet.viz.replay import replay_html

    t0 = time.perf_counter()
    page_bytes = replay_html(rec)
    build_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as pw:
        path = Path(tmp) / "replay.html"
        path.write_bytes(page_bytes)
        browser = pw.chromium.launch(executable_path="/usr/bin/chromium", args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        t0 = time.perf_counter()
        page.goto(path.as_uri())
        page.wait_for_function("window.amronetReplay && window.amronetReplay.draws > 0", timeout=120_000)
        load_s = time.perf_counter() - t0
        frames = page.evaluate("""() => { const a = window.amronetReplay, t = [];
            const step = Math.max(1, Math.floor(a.frames / 200));
            for (let f = 0; f < a.frames; f += step) { a.seek(f); t.push(a.drawNow(true)); }
            return t; }""")
        page.evaluate("window.amronetReplay.seek(0)")
        page.select_option("#speed", "16")
        draws0 = page.evaluate("window.amronetReplay.draws")
        t0 = time.perf_counter()
        page.click("#play")
        page.wait_for_timeout(3000)
        fps = (page.evaluate("window.amronetReplay.draws") - draws0) / (time.perf_counter() - t0)
        browser.close()
    frames.sort()
    return {
        "replay_html_mb": round(len(page_bytes) / 1e6, 2),
        "replay_build_s": round(build_s, 2),
        "replay_load_s": round(load_s, 2),
        "replay_draw_ms_median": round(statistics.median(frames), 1),
        "replay_draw_ms_p95": round(frames[int(0.95 * (len(frames) - 1))], 1),
        "replay_playing_fps": round(fps, 1),
    }


def run(robots: int, steps: int, every: int, replay: bool = False) -> dict:
    """Step ``steps`` times with a recorder; return sizes and timings."""
    sim = bench_simulation(robots)
    rec = Recorder(every=every)
    sim.step()  # warm-up (numba from cache)
    sim.steps = 0
    rec.observe(sim)
    step_s = observe_s = 0.0
    clock = time.perf_counter
    for k in range(steps):
        t0 = clock()
        sim.step()
        t1 = clock()
        if k == steps - 1:
            sim.stop_reason = "time_limit"
        rec.observe(sim)
        step_s += t1 - t0
        observe_s += clock() - t1
    t0 = clock()
    blob = rec.npz_bytes(sim)
    encode_s = clock() - t0
    t0 = clock()
    with np.load(io.BytesIO(blob)) as data:
        loaded = Recording.from_arrays({k: data[k] for k in data.files})
    load_s = clock() - t0
    frames = len(rec)
    n = int(loaded.n.max())
    raw = frames * n * (2 * 8 + 1 + 4)  # float64 positions, int8 state, int32 status
    err = float(np.abs(loaded.xy[-1] - sim.swarm.xy).max())
    states = sim.state_counts()
    extra = replay_timing(loaded) if replay else {}
    return {
        "robots": n,
        "steps": steps,
        "every": every,
        "frames": frames,
        "npz_bytes": len(blob),
        "npz_mb": round(len(blob) / 1e6, 2),
        "bytes_per_robot_frame": round(len(blob) / (frames * n), 3),
        "raw_float64_mb": round(raw / 1e6, 1),
        "observe_ms_per_frame": round(1e3 * observe_s / frames, 3),
        "recorder_share_of_step_time": round(observe_s / step_s, 4),
        "step_s": round(step_s, 2),
        "encode_s": round(encode_s, 2),
        "load_s": round(load_s, 2),
        "max_position_error_m": err,
        "quantum_m": loaded.xy_quantum,
        "final_states": states,
        **extra,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--robots", type=int, default=3000)
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--every", type=int, default=10)
    parser.add_argument("--replay", action="store_true", help="also time the replay page in headless Chromium")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    report = run(args.robots, args.steps, args.every, replay=args.replay)
    if args.json:
        print(json.dumps(report, indent=2))
        return
    for key, value in report.items():
        print(f"{key:>30}: {value}")


if __name__ == "__main__":
    main()
