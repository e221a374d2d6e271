"""Tests of amronet.viz.recorded: snapshots of recorded frames (PNG, SVG) and animations (GIF, MP4), by content."""

from __future__ import annotations

import io
import itertools
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from PIL import Image

from amronet.engine.robots import Role, State
from amronet.errors import AmronetError
from amronet.outputs.recording import Recorder, Recording
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.viz.nodestyle import PALETTE
from amronet.viz.recorded import FrameRenderer, pick_frames, recording_snapshot, write_animation
from amronet.viz.snapshot import MAP_COLOURS

DPI = 60
SVG = "{http://www.w3.org/2000/svg}"


def _recording(preset: str, overrides: dict, every: int = 10) -> Recording:
    sim = Simulation(load_scenario(preset, overrides), 1)
    result = sim.run(recorder=Recorder(every))
    with np.load(io.BytesIO(result.files()["recording.npz"])) as data:
        return Recording.from_arrays({k: data[k] for k in data.files})


@pytest.fixture(scope="module")
def spread() -> Recording:
    return _recording("self-spreading-autolab", {"sim.time_limit": 40})


@pytest.fixture(scope="module")
def agents() -> Recording:
    return _recording("agent-assisted-office", {"sim.time_limit": 150})


def _png(fig) -> np.ndarray:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return np.asarray(Image.open(buf).convert("RGB"), dtype=np.int16)


def _pixel(fig, xy) -> tuple[int, int]:
    fig.canvas.draw()
    px, py = fig.axes[0].transData.transform(xy)
    return int(np.rint(fig.get_figheight() * fig.dpi - py)), int(np.rint(px))


def test_snapshot_png_shows_routers_in_their_status_colour(spread):
    f = spread.frames - 1
    fig = recording_snapshot(spread, f, dpi=DPI)
    img = _png(fig)
    fr = spread.frame(f)
    blue = np.rint(255 * PALETTE[0])
    base = np.flatnonzero(fr["kind"] == Role.BASE)[0]
    r, c = _pixel(fig, fr["xy"][base])
    assert np.abs(img[r, c] - blue).max() <= 12  # the base station's square, status 0
    refs = np.flatnonzero(fr["state"] == State.REFERENCE)
    assert len(refs) >= 3
    hits = [np.abs(img[_pixel(fig, fr["xy"][i])] - blue).max() <= 30 for i in refs]
    assert np.mean(hits) >= 0.8  # a neighbour's marker may sit on top of a few
    uncovered = np.all(np.abs(img - np.array(MAP_COLOURS["uncovered"])) <= 6, axis=-1)
    assert uncovered.sum() > 1000  # 40 s in, most of autolab is uncovered
    assert "coverage" in fig.axes[0].get_title() and "t = 40 s" in fig.axes[0].get_title()


def test_snapshot_svg_has_one_marker_per_robot_one_disk_per_deployed_node_one_line_per_link(spread):
    f = spread.frames - 1
    fig = recording_snapshot(spread, f, dpi=DPI)
    buf = io.StringIO()
    fig.savefig(buf, format="svg")
    root = ET.fromstring(buf.getvalue())
    groups = {g.get("id"): g for g in root.iter(f"{SVG}g") if g.get("id")}
    markers = sum(len(list(g.iter(f"{SVG}use"))) for k, g in groups.items() if k.startswith("PathCollection"))
    assert markers == spread.n[f]
    fr = spread.frame(f)
    deployed = np.isin(fr["state"], (State.BASE, State.REFERENCE, State.TRIANGLE_SETTLED)).sum()
    disks = [g for k, g in groups.items() if k.startswith("EllipseCollection")]
    assert len(disks) == 1 and len(list(disks[0].iter(f"{SVG}use"))) == deployed
    links = [g for k, g in groups.items() if k.startswith("LineCollection")]
    assert len(links) == 1 and len(list(links[0].iter(f"{SVG}path"))) == len(spread.links(f))


def test_snapshot_draws_agent_trails(agents):
    f = agents.frames - 1
    fig = recording_snapshot(agents, f, dpi=DPI)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "agent trail" in labels and "agent" in labels
    trails = agents.trails(f)
    assert len(trails) == 3
    collections = [c for c in fig.axes[0].collections if c.get_zorder() == 2.5]
    assert len(collections) == 1 and len(collections[0].get_segments()) == 3
    # a trail's midpoint is drawn in its agent's status colour (or a blend with the map under it)
    img = _png(fig)
    path = next(iter(trails.values()))
    r, c = _pixel(fig, path[len(path) // 2])
    window = img[r - 2: r + 3, c - 2: c + 3].reshape(-1, 3)
    assert np.any(window[:, 2] - window[:, 0] > 40)  # bluish


def test_gif_frames_count_and_differ(spread, tmp_path):
    path = tmp_path / "run.gif"
    count = write_animation(spread, path, fps=5, max_frames=8, dpi=40)
    assert count == 8 == len(pick_frames(spread.frames, 1, 8))
    im = Image.open(path)
    assert im.n_frames == 8
    assert im.info["duration"] == 200 and im.info["loop"] == 0
    frames = []
    for k in range(im.n_frames):
        im.seek(k)
        frames.append(np.asarray(im.convert("RGB"), dtype=np.int16))
    assert all(np.abs(a - b).sum() > 0 for a, b in itertools.pairwise(frames))
    assert frames[0].shape == frames[-1].shape


def test_renderer_matches_the_snapshot_layout(spread):
    renderer = FrameRenderer(spread, dpi=DPI)
    a = renderer.render(0)
    b = renderer.render(spread.frames - 1)
    assert a.shape == b.shape == _png(recording_snapshot(spread, 0, dpi=DPI)).shape
    assert np.abs(a.astype(int) - b).sum() > 0
    labels = [t.get_text() for t in renderer.fig.legends[0].get_texts()]
    assert labels.index("covered: within $r_c$ of any\nrouter or base (moving too)") + 1 == \
        labels.index("reachable, uncovered")


def test_pick_frames():
    assert pick_frames(10).tolist() == list(range(10))
    assert pick_frames(10, every=4).tolist() == [0, 4, 8, 9]
    picked = pick_frames(1000, max_frames=50)
    assert len(picked) == 50 and picked[0] == 0 and picked[-1] == 999
    with pytest.raises(AmronetError, match="--every"):
        pick_frames(10, every=0)


def test_mp4(spread, tmp_path):
    pytest.importorskip("imageio_ffmpeg")
    path = tmp_path / "run.mp4"
    assert write_animation(spread, path, max_frames=6, dpi=40) == 6
    head = path.read_bytes()[:64]
    assert b"ftyp" in head and path.stat().st_size > 1000


def test_mp4_without_encoder_is_a_one_line_error(spread, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    with pytest.raises(AmronetError, match=r"needs an encoder: pip install 'amronet\[video\]'"):
        write_animation(spread, tmp_path / "run.mp4")
    assert not (tmp_path / "run.mp4").exists()
    with pytest.raises(AmronetError, match=r"must end in .gif or .mp4"):
        write_animation(spread, tmp_path / "run.avi")


def test_fps_bounds(spread, tmp_path):
    for fps, fmt in ((51, "gif"), (0.005, "gif"), (-1, "gif"), (float("inf"), "gif"), (121, "mp4")):
        with pytest.raises(AmronetError, match=rf"--fps: .* frames per second for {fmt.upper()}"):
            write_animation(spread, tmp_path / f"run.{fmt}", fps=fps)
    assert list(tmp_path.iterdir()) == []
    assert write_animation(spread, tmp_path / "run.gif", fps=50, max_frames=2, dpi=20) == 2
    assert Image.open(tmp_path / "run.gif").info["duration"] == 20


def test_renderer_draws_the_static_parts_once_and_matches_a_full_draw(agents, monkeypatch):
    renderer = FrameRenderer(agents, dpi=DPI)
    fig = renderer.fig
    drawn = {"legend": 0, "xaxis": 0}
    for name, artist in (("legend", fig.legends[0]), ("xaxis", renderer.ax.xaxis)):
        draw = artist.draw

        def counting(*args, _draw=draw, _name=name, **kwargs):
            drawn[_name] += 1
            return _draw(*args, **kwargs)

        monkeypatch.setattr(artist, "draw", counting)
    f = agents.frames // 2
    blitted = [renderer.render(g) for g in (0, agents.frames - 1, f)][-1].astype(int)
    assert drawn == {"legend": 0, "xaxis": 0}  # only what changes is drawn per frame
    # the same figure drawn in full, every artist at once, shows the same picture
    for artist in renderer._animated:
        artist.set_animated(False)
    fig.canvas.draw()
    full = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    assert blitted.shape == full.shape
    differ = np.abs(blitted - full).max(axis=-1) > 40
    assert differ.mean() < 0.002  # the uncovered tint is averaged by a different filter: edges may differ a bit
    assert "coverage" in renderer.title.get_text() and f"t = {agents.t[f]:g} s" in renderer.title.get_text()


def test_renderer_tint_marks_uncovered_ground(spread):
    renderer = FrameRenderer(spread, dpi=DPI)
    img = renderer.render(0).astype(int)
    light_red = np.all(np.abs(img - np.array(MAP_COLOURS["uncovered"])) <= 8, axis=-1)
    assert light_red.sum() > 1000  # at t = 0 almost nothing is covered
    plain = FrameRenderer(spread, dpi=DPI, layers=("disks", "links", "trails")).render(0).astype(int)
    assert np.all(np.abs(plain - np.array(MAP_COLOURS["uncovered"])) <= 8, axis=-1).sum() < 0.01 * light_red.sum()


def test_gif_shares_one_palette_and_stores_only_changes(spread, tmp_path):
    path = tmp_path / "run.gif"
    assert write_animation(spread, path, max_frames=12, dpi=DPI) == 12
    # the same frames, each quantized on its own and stored whole (how GIFs were written before)
    frames = list(FrameRenderer(spread, dpi=DPI).frames(pick_frames(spread.frames, 1, 12)))
    images = [Image.fromarray(rgb).quantize(colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
              for rgb in frames]
    whole = io.BytesIO()
    images[0].save(whole, format="GIF", save_all=True, append_images=images[1:], duration=100, loop=0,
                   optimize=False, disposal=1)
    assert path.stat().st_size < 0.6 * len(whole.getvalue())
    im = Image.open(path)
    for k in (0, 5, 11):  # and each frame still shows its picture
        im.seek(k)
        shown = np.asarray(im.convert("RGB"), dtype=int)
        assert np.mean(np.abs(shown - frames[k]).max(axis=-1) > 40) < 0.002
