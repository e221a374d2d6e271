"""Tests of amronet.world.loading: ROS map_server YAML + image → OccupancyMap."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from amronet.errors import MapError
from amronet.world import FREE, OCCUPIED, UNKNOWN, load_map_yaml

MAPS_DIR = Path(str(resources.files("amronet").joinpath("data", "maps")))

YAML_DEFAULTS = {
    "image": "map.png",
    "resolution": "0.1",
    "origin": "[1.0, -2.0, 0.0]",
    "negate": "0",
    "occupied_thresh": "0.65",
    "free_thresh": "0.196",
}


def write_yaml(folder: Path, name: str = "map", drop: tuple[str, ...] = (), **values: str) -> Path:
    """Write a map YAML built from YAML_DEFAULTS, with keys overridden (values are raw YAML text)."""
    entries = {**YAML_DEFAULTS, **values}
    text = "".join(f"{k}: {v}\n" for k, v in entries.items() if k not in drop)
    path = folder / f"{name}.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def write_map(folder: Path, img: Image.Image, image_name: str = "map.png", **values: str) -> Path:
    """Save ``img`` and a YAML naming it; return the YAML path."""
    img.save(folder / image_name)
    return write_yaml(folder, image=image_name, **values)


def grey(rows: list[list[int]]) -> Image.Image:
    """An 8-bit grey image from rows listed top first, as seen in a picture."""
    return Image.fromarray(np.array(rows, dtype=np.uint8))


# --- real maps --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "width", "height", "licence"),
    [
        ("cave", 16.0, 16.0, "GPL-2.0"),
        ("autolab", 20.0, 17.0, "GPL-2.0"),
        ("hospital_section", 40.0, 16.0, "GPL-2.0"),
        ("depot", 30.0, 15.0, "Apache-2.0"),
    ],
)
def test_real_maps_load_with_readme_sizes(name: str, width: float, height: float, licence: str) -> None:
    omap = load_map_yaml(MAPS_DIR / f"{name}.yaml")
    assert omap.name == name
    assert omap.cells.dtype == np.int8
    assert set(np.unique(omap.cells)) <= {FREE, OCCUPIED, UNKNOWN}
    w, h = omap.size_m
    assert w == pytest.approx(width, abs=0.5)
    assert h == pytest.approx(height, abs=0.5)
    assert omap.licence is not None and omap.licence.startswith(licence)
    assert 0.02 < (omap.cells == OCCUPIED).mean() < 0.2
    assert omap.free.mean() > 0.5
    assert omap.source == str(MAPS_DIR / f"{name}.yaml")


def test_cave_origin_and_resolution() -> None:
    omap = load_map_yaml(MAPS_DIR / "cave.yaml")
    assert omap.origin == (-8.0, -8.0)
    assert omap.resolution == 0.032
    assert omap.extent == pytest.approx((-8.0, 8.0, -8.0, 8.0))


def test_depot_unknown_grey_counts_as_free_under_its_free_thresh() -> None:
    # depot.pgm marks unknown space 205: p = 50/255 = 0.196 < free_thresh 0.25, so map_server calls it free.
    omap = load_map_yaml(MAPS_DIR / "depot.yaml")
    assert not (omap.cells == UNKNOWN).any()


# --- pixel semantics --------------------------------------------------------------------------------------


def test_rows_are_flipped_so_the_picture_top_is_the_highest_row(tmp_path: Path) -> None:
    path = write_map(tmp_path, grey([[0, 0, 0, 0], [255] * 4, [255] * 4]))
    omap = load_map_yaml(path)
    assert omap.shape == (3, 4)
    assert (omap.cells[-1] == OCCUPIED).all()
    assert (omap.cells[:-1] == FREE).all()
    # ... of the world too: rows are 0.1 m from y = -2, so the top row spans y -1.8..-1.7
    assert omap.is_free(np.array([[1.05, -1.85]]))[0]
    assert not omap.is_free(np.array([[1.05, -1.75]]))[0]


def test_metadata(tmp_path: Path) -> None:
    path = write_map(tmp_path, grey([[255, 255]]), licence='"CC0, drawn by hand"')
    omap = load_map_yaml(path)
    assert omap.name == "map"
    assert omap.resolution == 0.1
    assert omap.origin == (1.0, -2.0)
    assert omap.licence == "CC0, drawn by hand"
    assert omap.size_m == pytest.approx((0.2, 0.1))


def test_licence_is_optional(tmp_path: Path) -> None:
    assert load_map_yaml(write_map(tmp_path, grey([[255]]))).licence is None


def test_image_path_is_relative_to_yaml_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    folder = tmp_path / "maps"
    folder.mkdir()
    path = write_map(folder, grey([[0, 255]]))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert load_map_yaml(Path("..") / "maps" / path.name).cells.tolist() == [[OCCUPIED, FREE]]


def test_absolute_image_path(tmp_path: Path) -> None:
    img_path = tmp_path / "pics" / "a.png"
    img_path.parent.mkdir()
    grey([[0, 255]]).save(img_path)
    path = write_yaml(tmp_path, image=str(img_path))
    assert load_map_yaml(path).cells.tolist() == [[OCCUPIED, FREE]]


def test_trinary_thresholds(tmp_path: Path) -> None:
    values = [0, 50, 100, 128, 200, 204, 206, 255]
    # p = (255 - v) / 255: 1.0 0.80 0.61 0.50 0.22 0.2 0.19 0.0
    omap = load_map_yaml(write_map(tmp_path, grey([values])))
    expected = [OCCUPIED, OCCUPIED, UNKNOWN, UNKNOWN, UNKNOWN, UNKNOWN, FREE, FREE]
    assert omap.cells[0].tolist() == expected


def test_thresholds_are_strict(tmp_path: Path) -> None:
    occ, free = (255 - 90) / 255, (255 - 210) / 255
    path = write_map(tmp_path, grey([[89, 90, 210, 211]]), occupied_thresh=repr(occ), free_thresh=repr(free))
    assert load_map_yaml(path).cells[0].tolist() == [OCCUPIED, UNKNOWN, UNKNOWN, FREE]


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    img = grey([[0, 128, 255]])
    plain = load_map_yaml(write_map(tmp_path, img))
    negated = load_map_yaml(write_map(tmp_path, img, negate="1"))
    assert plain.cells[0].tolist() == [OCCUPIED, UNKNOWN, FREE]
    assert negated.cells[0].tolist() == [FREE, UNKNOWN, OCCUPIED]
    assert load_map_yaml(write_map(tmp_path, img, negate="true")).cells[0].tolist() == [
        FREE,
        UNKNOWN,
        OCCUPIED,
    ]


def test_scale_mode_matches_trinary_for_opaque_images(tmp_path: Path) -> None:
    img = grey([[0, 50, 100, 128, 200, 255]])
    trinary = load_map_yaml(write_map(tmp_path, img))
    scale = load_map_yaml(write_map(tmp_path, img, mode="scale"))
    np.testing.assert_array_equal(trinary.cells, scale.cells)


def test_raw_mode(tmp_path: Path) -> None:
    omap = load_map_yaml(write_map(tmp_path, grey([[0, 10, 50, 100, 101, 255]]), mode="raw"))
    # value/100 against the thresholds: 0 and 10 free, 50 unknown, 100 occupied; > 100 unknown
    assert omap.cells[0].tolist() == [FREE, FREE, UNKNOWN, OCCUPIED, UNKNOWN, UNKNOWN]
    negated = load_map_yaml(write_map(tmp_path, grey([[255, 155, 0]]), mode="raw", negate="1"))
    assert negated.cells[0].tolist() == [FREE, OCCUPIED, UNKNOWN]


def test_one_bit_png(tmp_path: Path) -> None:
    img = Image.new("1", (3, 2), color=1)
    img.putpixel((0, 0), 0)
    img.putpixel((2, 1), 0)
    omap = load_map_yaml(write_map(tmp_path, img))
    # picture row 0 (top) is grid row 1
    assert omap.cells.tolist() == [[FREE, FREE, OCCUPIED], [OCCUPIED, FREE, FREE]]


def test_palette_png_uses_palette_greys_not_indices(tmp_path: Path) -> None:
    img = Image.new("P", (3, 1))
    img.putpalette([255, 255, 255, 0, 0, 0, 128, 128, 128] + [0, 0, 0] * 253)
    img.putdata([0, 1, 2])  # white, black, mid grey
    omap = load_map_yaml(write_map(tmp_path, img))
    assert omap.cells[0].tolist() == [FREE, OCCUPIED, UNKNOWN]


def test_palette_png_transparency_is_unknown(tmp_path: Path) -> None:
    img = Image.new("P", (2, 1))
    img.putpalette([255, 255, 255, 250, 250, 250] + [0, 0, 0] * 254)
    img.putdata([0, 1])
    img.info["transparency"] = 1
    img.save(tmp_path / "t.png", transparency=1)
    omap = load_map_yaml(write_yaml(tmp_path, image="t.png"))
    assert omap.cells[0].tolist() == [FREE, UNKNOWN]


def test_rgb_uses_channel_average(tmp_path: Path) -> None:
    rgb = np.array([[[255, 255, 255], [0, 255, 0], [255, 255, 0], [0, 0, 0]]], dtype=np.uint8)
    omap = load_map_yaml(write_map(tmp_path, Image.fromarray(rgb)))
    # green averages to 85 (p 0.67, occupied; luma would say 150, unknown); yellow to 170 (p 0.33, unknown)
    assert omap.cells[0].tolist() == [FREE, OCCUPIED, UNKNOWN, OCCUPIED]


def test_rgba_fully_transparent_is_unknown(tmp_path: Path) -> None:
    rgba = np.array(
        [[[255, 255, 255, 255], [255, 255, 255, 0], [0, 0, 0, 0], [0, 0, 0, 128]]], dtype=np.uint8
    )
    omap = load_map_yaml(write_map(tmp_path, Image.fromarray(rgba)))
    assert omap.cells[0].tolist() == [FREE, UNKNOWN, UNKNOWN, OCCUPIED]


def test_pgm_and_16_bit_grey(tmp_path: Path) -> None:
    omap = load_map_yaml(write_map(tmp_path, grey([[0, 205, 254]]), image_name="m.pgm"))
    assert omap.cells[0].tolist() == [OCCUPIED, UNKNOWN, FREE]
    img16 = Image.fromarray(np.array([[0, 205 * 257, 65535]], dtype=np.uint16))
    omap16 = load_map_yaml(write_map(tmp_path, img16, image_name="m16.png"))
    assert omap16.cells[0].tolist() == [OCCUPIED, UNKNOWN, FREE]


# --- bad input --------------------------------------------------------------------------------------------


def check_error(exc: pytest.ExceptionInfo[MapError], field: str) -> None:
    assert exc.value.field == field
    text = str(exc.value)
    assert text.startswith(f"{field}: ")
    assert "\n" not in text
    assert len(exc.value.message) > 10


def test_missing_yaml(tmp_path: Path) -> None:
    with pytest.raises(MapError) as exc:
        load_map_yaml(tmp_path / "nope.yaml")
    check_error(exc, "map")
    assert "nope.yaml" in str(exc.value)


def test_yaml_is_a_folder(tmp_path: Path) -> None:
    with pytest.raises(MapError) as exc:
        load_map_yaml(tmp_path)
    check_error(exc, "map")


@pytest.mark.parametrize("text", ["image: [unclosed\nresolution: 1\n", "- a\n- b\n", "", "just text\n"])
def test_yaml_not_a_mapping(tmp_path: Path, text: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(MapError) as exc:
        load_map_yaml(path)
    check_error(exc, "map")


@pytest.mark.parametrize("key", ["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"])
def test_missing_key(tmp_path: Path, key: str) -> None:
    grey([[255]]).save(tmp_path / "map.png")
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path, drop=(key,)))
    check_error(exc, f"map.{key}")


def test_unknown_key(tmp_path: Path) -> None:
    grey([[255]]).save(tmp_path / "map.png")
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path, resolutoin="0.1"))
    check_error(exc, "map.resolutoin")
    assert "resolution" in exc.value.message


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("resolution", "0"),
        ("resolution", "-0.05"),
        ("resolution", ".nan"),
        ("resolution", ".inf"),
        ("resolution", "fine"),
        ("resolution", "true"),
        ("origin", "[0.0, 0.0, 0.5]"),
        ("origin", "[0.0, 0.0]"),
        ("origin", "[0.0, x, 0.0]"),
        ("origin", "0.0"),
        ("negate", "2"),
        ("negate", "0.5"),
        ("occupied_thresh", "1.5"),
        ("occupied_thresh", "-0.1"),
        ("free_thresh", "-0.1"),
        ("free_thresh", "0.65"),
        ("free_thresh", "0.9"),
        ("mode", "bogus"),
        ("image", "42"),
        ("image", '""'),
        ("licence", "[1, 2]"),
    ],
)
def test_bad_values(tmp_path: Path, key: str, value: str) -> None:
    grey([[255]]).save(tmp_path / "map.png")
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path, **{key: value}))
    check_error(exc, f"map.{key}")


def test_image_missing(tmp_path: Path) -> None:
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path, image="absent.png"))
    check_error(exc, "map.image")
    assert "absent.png" in str(exc.value)


@pytest.mark.parametrize("content", [b"this is not an image\n", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00"])
def test_image_not_an_image(tmp_path: Path, content: bytes) -> None:
    (tmp_path / "map.png").write_bytes(content)
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path))
    check_error(exc, "map.image")


def test_truncated_image(tmp_path: Path) -> None:
    grey([[0, 255] * 50] * 50).save(tmp_path / "full.png")
    data = (tmp_path / "full.png").read_bytes()
    (tmp_path / "map.png").write_bytes(data[: len(data) // 2])
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path))
    check_error(exc, "map.image")


def test_unsupported_image_mode(tmp_path: Path) -> None:
    Image.new("CMYK", (2, 2)).save(tmp_path / "map.tif")
    with pytest.raises(MapError) as exc:
        load_map_yaml(write_yaml(tmp_path, image="map.tif"))
    check_error(exc, "map.image")


def test_map_error_is_a_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="not found"):
        load_map_yaml(tmp_path / "nope.yaml")
