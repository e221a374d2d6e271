"""The replay page in a real headless Chromium (Debian's package), driven by Playwright.

``make test`` installs Chromium when ``/usr/bin/chromium`` is missing, so this test runs in CI. It is skipped
only when ``AMRONET_SKIP_BROWSER=1`` is set explicitly; a missing browser or Playwright otherwise fails it.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from amronet.cli import main

CHROMIUM = os.environ.get("AMRONET_CHROMIUM", "/usr/bin/chromium")
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]

if os.environ.get("AMRONET_SKIP_BROWSER") == "1":
    pytest.skip("AMRONET_SKIP_BROWSER=1: browser test skipped on request", allow_module_level=True)

# The canvas's pixels, read from a copy made for reading (reading the page's own canvas again and again makes
# Chromium warn).
PIXELS = """const pixels = () => {
  const v = document.getElementById('view'), c = document.createElement('canvas');
  c.width = v.width; c.height = v.height;
  const g = c.getContext('2d', {willReadFrequently: true}); g.drawImage(v, 0, 0);
  return g.getImageData(0, 0, c.width, c.height);
};"""
# What the canvas shows, as numbers: pixels that are not white, and distinct colours among a sample.
CANVAS_STATS = """() => { """ + PIXELS + """
  const d = pixels().data;
  let ink = 0; const colours = new Set();
  for (let i = 0; i < d.length; i += 4) {
    if (d[i] < 250 || d[i + 1] < 250 || d[i + 2] < 250) ink++;
    if (i % 64 === 0) colours.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
  }
  return {ink, pixels: d.length / 4, colours: colours.size};
}"""
CANVAS_HASH = """() => { """ + PIXELS + """
  const d = pixels().data;
  let h = 0; for (let i = 0; i < d.length; i += 7) h = (h * 31 + d[i]) | 0; return h;
}"""


@pytest.fixture(scope="module")
def page_file(tmp_path_factory) -> Path:
    runs = tmp_path_factory.mktemp("replay")
    argv = ["run", "--preset", "self-spreading-autolab", "--set", "sim.time_limit=60", "--seed", "1", "-q",
            "--out", str(runs / "a"), "--record"]
    assert main(argv) == 0
    assert main(["replay", str(runs / "a"), "--out", str(runs / "replay.html"), "-q"]) == 0
    return runs / "replay.html"


_BS = ", ".join(f"{{x: {x}, y: {y}}}" for y in (-2.5, 2.5) for x in (-2.5, -1.5, -0.5, 0.5, 1.5))
MANY_BS = f"""name: many-bs
description: "10 base stations along two edges of the open field, one router"
map: open-6x6
algorithm: {{name: self-spreading, params: {{triangular: local}}}}
radio: {{model: unit-disk, r_c: 1.0}}
base_stations: [{_BS}]
routers: {{count: 1}}
sim: {{dt: 0.1, time_limit: 5.0, record_every: 10}}
"""


@pytest.fixture(scope="module")
def many_bs_file(tmp_path_factory) -> Path:
    """A replay of 10 base stations (more than the 8 status colours) and a single router."""
    runs = tmp_path_factory.mktemp("replay-many")
    (runs / "many.yaml").write_text(MANY_BS)
    assert main(["run", str(runs / "many.yaml"), "--seed", "1", "-q", "--out", str(runs / "a"), "--record"]) == 0
    assert main(["replay", str(runs / "a"), "--out", str(runs / "replay.html"), "-q"]) == 0
    return runs / "replay.html"


@pytest.fixture(scope="module")
def browser():
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("Playwright is missing: pip install -e '.[dev]' (or set AMRONET_SKIP_BROWSER=1)")
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: make test installs it (apt-get install chromium), "
                    "or set AMRONET_SKIP_BROWSER=1")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, page_file):
    pg = browser.new_page(viewport={"width": 1280, "height": 900})
    problems: list[str] = []
    pg.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type in ("error", "warning")
          else None)
    pg.on("pageerror", lambda e: problems.append(f"page error: {e}"))
    pg.on("request", lambda r: problems.append(f"request: {r.url}") if not r.url.startswith(("file:", "data:",
                                                                                            "blob:")) else None)
    pg.goto(page_file.as_uri())
    pg.wait_for_function("window.amronetReplay && window.amronetReplay.ready && window.amronetReplay.draws > 0",
                         timeout=30_000)
    pg.problems = problems
    yield pg
    pg.close()


def test_loads_without_errors_and_draws(page):
    stats = page.evaluate(CANVAS_STATS)
    assert stats["ink"] > 0.2 * stats["pixels"]  # map, walls, disks, robots: not a blank canvas
    assert stats["colours"] > 20
    assert page.evaluate("window.amronetReplay.frames") == 61
    assert page.locator("#error").inner_text() == ""
    assert page.problems == []


def test_base_station_is_drawn_in_its_status_colour(page):
    page.locator("#layer-disks").uncheck()
    page.locator("#layer-links").uncheck()
    page.wait_for_function("!window.amronetReplay.layers.disks")
    page.wait_for_timeout(100)
    colour = page.evaluate("""() => { """ + PIXELS + """
      const a = window.amronetReplay, [x, y] = a.position(a.frame, 0), [px, py] = a.worldToPage(x, y);
      const r = document.getElementById('view').getBoundingClientRect(), img = pixels(), k = img.width / r.width;
      const i = 4 * (Math.round((py - r.top) * k) * img.width + Math.round((px - r.left) * k));
      return Array.from(img.data.slice(i, i + 3));
    }""")
    assert max(abs(a - b) for a, b in zip(colour, (0x1F, 0x77, 0xB4), strict=True)) <= 12  # tab10 blue: status 0
    assert page.problems == []


def test_play_advances_time(page):
    before = page.locator("#time").inner_text()
    assert page.evaluate("window.amronetReplay.frame") == 0
    page.locator("#speed").select_option("4")
    page.locator("#play").click()
    page.wait_for_function("window.amronetReplay.frame >= 5", timeout=10_000)
    assert page.evaluate("window.amronetReplay.playing")
    page.locator("#play").click()
    assert not page.evaluate("window.amronetReplay.playing")
    frame = page.evaluate("window.amronetReplay.frame")
    page.wait_for_timeout(300)
    assert page.evaluate("window.amronetReplay.frame") == frame  # paused
    assert page.locator("#time").inner_text() != before
    assert int(page.locator("#slider").input_value()) == frame
    assert page.problems == []


def test_slider_moves_the_frame_and_the_picture(page):
    first = page.evaluate(CANVAS_HASH)
    page.locator("#slider").fill("40")
    page.wait_for_function("window.amronetReplay.frame === 40")
    page.wait_for_timeout(100)
    assert page.evaluate(CANVAS_HASH) != first
    assert "t = 40.0 s" in page.locator("#time").inner_text()
    page.keyboard.press("ArrowRight")
    page.wait_for_function("window.amronetReplay.frame === 41")
    assert page.problems == []


def test_layer_toggles_change_the_picture(page):
    page.locator("#slider").fill("60")
    page.wait_for_function("window.amronetReplay.frame === 60")
    page.wait_for_timeout(100)
    hashes = {"all": page.evaluate(CANVAS_HASH)}
    for name in ("uncovered", "disks", "links", "trails"):
        page.locator(f"#layer-{name}").uncheck()
        page.wait_for_function(f"!window.amronetReplay.layers.{name}")
        page.wait_for_timeout(80)
        hashes[name] = page.evaluate(CANVAS_HASH)
    assert len(set(hashes.values())) == 5
    assert page.problems == []


def test_hover_shows_id_state_and_status(page):
    page.locator("#slider").fill("60")
    page.wait_for_function("window.amronetReplay.frame === 60")
    x, y = page.evaluate("""() => { const a = window.amronetReplay; const p = a.position(60, 0);
                                    return a.worldToPage(p[0], p[1]); }""")
    page.mouse.move(x, y)
    page.wait_for_function("window.amronetReplay.hover !== null")
    assert page.evaluate("window.amronetReplay.hover") == {"id": 0, "kind": "base", "state": "base", "status": 0}
    tip = page.locator("#tip")
    assert tip.is_visible() and "#0 base" in tip.inner_text() and "BS 0" in tip.inner_text()
    page.mouse.move(1, 1)
    page.wait_for_function("window.amronetReplay.hover === null")
    assert page.problems == []


def test_chart_click_seeks(page):
    box = page.locator("#chart").bounding_box()
    page.mouse.click(box["x"] + box["width"] * 0.5, box["y"] + box["height"] / 2)
    page.wait_for_function("window.amronetReplay.frame > 20 && window.amronetReplay.frame < 40")
    assert page.problems == []


def test_scale_bar_is_below_the_map_to_scale(page):
    view = page.locator("#view").bounding_box()
    bar = page.locator("#scalebar-bar").bounding_box()
    label = page.locator("#scalebar-label").bounding_box()
    for box in (bar, label):  # outside the canvas: below it, so it hides no node
        assert box["y"] >= view["y"] + view["height"] - 0.5
        assert view["x"] - 0.5 <= box["x"] and box["x"] + box["width"] <= view["x"] + view["width"] + 0.5
    assert abs(bar["x"] + bar["width"] - (view["x"] + view["width"])) <= 1  # right-aligned with the map
    chart = page.locator("#chart").bounding_box()
    assert label["y"] + label["height"] <= chart["y"] + 0.5
    metres = float(page.locator("#scalebar-label").inner_text().removesuffix(" m"))
    (x0, _), (x1, _) = page.evaluate(f"[window.amronetReplay.worldToPage(0, 0), "
                                     f"window.amronetReplay.worldToPage({metres}, 0)]")
    assert abs(bar["width"] - (x1 - x0)) <= 1
    assert page.problems == []


def test_one_router_is_singular_and_repeated_colours_are_summed_up(browser, many_bs_file):
    pg = browser.new_page(viewport={"width": 1280, "height": 900})
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.goto(many_bs_file.as_uri())
    pg.wait_for_function("window.amronetReplay && window.amronetReplay.ready && window.amronetReplay.draws > 0",
                         timeout=30_000)
    numbers = pg.locator("#numbers").inner_text()
    assert "10 nodes" in numbers and "1 router moving" in numbers  # frame 0: the router still explores
    assert "11 robots" in pg.locator("#title").inner_text()
    legend = pg.locator("#legend").inner_text()
    assert "no base station yet" in legend and "base station 6" in legend
    assert "base station 7" not in legend and "base station 9" not in legend  # their colours repeat
    assert "… 3 more base stations (colours repeat)" in legend
    assert errors == []
    pg.close()
