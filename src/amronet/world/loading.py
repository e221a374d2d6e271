"""Loading ROS ``map_server`` maps: a YAML file naming an image, read into an :class:`OccupancyMap`.

The YAML keys and their meaning follow ROS ``map_server`` (ROS 1 ``image_loader``):

* ``image`` (required): image file, relative to the YAML file's folder unless absolute.
* ``resolution`` (required): metres per pixel, finite, between ``1e-6`` and ``1e6``.
* ``origin`` (required): ``[x, y, yaw]``, world pose of the lower-left pixel; only ``yaw == 0`` is supported. The
  map must lie within ``MAX_COORDINATE_M`` (10^9 m) of the world origin, so that positions and cell indices stay
  exact, finite numbers.
* ``negate`` (required): ``0``/``1`` (or ``false``/``true``, ``no``/``yes``, ``off``/``on``); ``1`` swaps black
  and white.
* ``occupied_thresh``, ``free_thresh`` (required): in ``[0, 1]`` with ``free_thresh < occupied_thresh``.
* ``mode`` (optional): ``trinary`` (default), ``scale`` or ``raw``.
* ``licence`` (optional, amronet's own addition): licence note of the map's source.

Any other key is an error, so that a misspelt key is not silently ignored. The file is read as scenario files are
(:func:`amronet.yaml_loading.load_yaml`: YAML 1.2's numbers and booleans, a key given twice refused).

Each pixel's grey value ``v`` is the mean of its colour channels (alpha excluded), as ``map_server`` does.
Then, in ``trinary`` and ``scale`` mode, ``p = (255 - v) / 255`` (``negate: 0``) or ``p = v / 255``
(``negate: 1``); ``p > occupied_thresh`` is ``OCCUPIED``, ``p < free_thresh`` is ``FREE`` and anything in
between is ``UNKNOWN``. ``scale`` mode gives the same cells as ``trinary``, because an occupancy grid of
three states has no room for ``map_server``'s intermediate probabilities. In ``raw`` mode the pixel value
itself (``255 - v`` when negated) is an occupancy percentage, as ``map_server`` publishes it: values
``0..100`` are thresholded as ``p = value / 100`` with the same thresholds (so ``0`` is free and ``100``
occupied), and any other value (``255`` is ``map_server``'s "unknown") is ``UNKNOWN``.

Before an image is decoded, its header's size is checked against the memory available (the resource guard,
:mod:`amronet.limits`: ``BYTES_PER_IMAGE_BAND`` per pixel and colour band, plus the grid), so that a huge image
is one line saying how much it would need, not a ``MemoryError`` halfway.

Fully transparent pixels (alpha 0, in RGBA, LA or palette images with transparency) are ``UNKNOWN`` in every
mode. This differs from ``map_server``'s trinary mode, which averages alpha in with the colour channels.

Supported images: anything Pillow opens in mode ``1``, ``L``, ``LA``, ``P``/``PA`` (the palette's colours
are used, not the indices), ``RGB``, ``RGBA`` or 16-bit grey (``I;16``/``I``, scaled to 8 bits), which
covers PGM, 1-bit/8-bit/palette/RGB(A) PNG, BMP and TIFF. Image rows are flipped so that row 0 of the
grid is the bottom of the picture.

Example:
    >>> omap = load_map_yaml("maps/cave.yaml")  # doctest: +SKIP
    >>> omap.size_m  # doctest: +SKIP
    (16.0, 16.0)
"""

from __future__ import annotations

import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, UnidentifiedImageError

from amronet import limits
from amronet.errors import MapError
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from amronet.yaml_loading import as_bool, load_yaml

__all__ = ["MAP_MODES", "MAP_YAML_KEYS", "MAX_COORDINATE_M", "image_occupancy", "load_map_yaml"]

MAP_MODES: tuple[str, ...] = ("trinary", "scale", "raw")
"""Values allowed for the ``mode`` key."""

_REQUIRED: tuple[str, ...] = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
_OPTIONAL: tuple[str, ...] = ("mode", "licence")

MAP_YAML_KEYS: frozenset[str] = frozenset(_REQUIRED + _OPTIONAL)
"""Every key a map YAML file may hold."""

MAX_COORDINATE_M = 1e9
"""Every corner of a map lies within this many metres of the world origin (a million kilometres: UTM coordinates
fit). Farther, cell indices and distances lose their precision or overflow."""
_RESOLUTION_RANGE = (1e-6, 1e6)


def _one_line(text: object) -> str:
    """Collapse any message (e.g. a multi-line YAML parser error) to one line."""
    return " ".join(str(text).split())


def _number(data: dict[str, Any], key: str) -> float:
    """Read a real number (not a bool, not a string) from the YAML mapping."""
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MapError(f"map.{key}", f"must be a number, got {value!r}; write e.g. '{key}: 0.05'")
    value = float(value)
    if not math.isfinite(value):
        raise MapError(f"map.{key}", f"must be a finite number, got {value!r}")
    return value


def _read_yaml(path: Path) -> dict[str, Any]:
    """Read the YAML file and check it is a mapping with exactly the known keys."""
    if not path.is_file():
        what = "is a folder, not a file" if path.is_dir() else "not found"
        raise MapError("map", f"map file '{path}' {what}; give the path of a ROS map_server YAML file")
    try:
        text = path.read_text(encoding="utf-8")
    except (UnicodeDecodeError, OSError) as exc:
        raise MapError("map", f"cannot read '{path}' as YAML ({_one_line(exc)}); fix the file") from None
    data = load_yaml(text, "map", f"'{path}'", error=MapError)
    if not isinstance(data, dict):
        raise MapError(
            "map", f"'{path}' holds a {type(data).__name__}, not a mapping; write 'key: value' lines"
        )
    unknown = sorted(str(k) for k in data if k not in MAP_YAML_KEYS)
    if unknown:
        raise MapError(
            f"map.{unknown[0]}",
            f"unknown key in '{path.name}'; allowed keys are {', '.join(sorted(MAP_YAML_KEYS))}",
        )
    missing = [k for k in _REQUIRED if k not in data]
    if missing:
        raise MapError(
            f"map.{missing[0]}",
            f"missing in '{path.name}'; a ROS map_server YAML needs {', '.join(_REQUIRED)}",
        )
    return data


def _parse_params(data: dict[str, Any]) -> tuple[float, tuple[float, float], bool, float, float, str]:
    """Validate the values of the YAML keys; return resolution, origin, negate, thresholds and mode."""
    resolution = _number(data, "resolution")
    if resolution <= 0:
        raise MapError("map.resolution", f"must be positive (metres per pixel), got {resolution!r}")
    low, high = _RESOLUTION_RANGE
    if not low <= resolution <= high:
        raise MapError("map.resolution", f"{resolution!r} metres per pixel is outside [{low:g}, {high:g}]; give "
                                         "the size of one pixel in metres, e.g. 0.05")

    origin = data["origin"]
    if not isinstance(origin, list | tuple) or len(origin) != 3:
        raise MapError("map.origin", f"must be a list [x, y, yaw], got {origin!r}")
    coords = []
    for value in origin:
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise MapError("map.origin", f"must hold three finite numbers [x, y, yaw], got {origin!r}")
        coords.append(float(value))
    if coords[2] != 0.0:
        raise MapError("map.origin", f"yaw {coords[2]!r} is not supported; rotate the image and set yaw to 0")
    if max(abs(coords[0]), abs(coords[1])) > MAX_COORDINATE_M:
        raise MapError("map.origin", f"[{coords[0]:g}, {coords[1]:g}] is more than {MAX_COORDINATE_M:g} m from the "
                                     "world origin; give the map's lower-left corner in metres near it")

    negate = as_bool(data["negate"])
    if negate not in (0, 1) or isinstance(negate, float):
        raise MapError("map.negate", f"must be 0 or 1, got {negate!r}")

    occ = _number(data, "occupied_thresh")
    free = _number(data, "free_thresh")
    for key, value in (("occupied_thresh", occ), ("free_thresh", free)):
        if not 0.0 <= value <= 1.0:
            raise MapError(f"map.{key}", f"must lie in [0, 1], got {value!r}")
    if free >= occ:
        raise MapError(
            "map.free_thresh", f"({free!r}) must be below occupied_thresh ({occ!r}); e.g. 0.196 and 0.65"
        )

    mode = data.get("mode", "trinary")
    if mode not in MAP_MODES:
        raise MapError("map.mode", f"must be one of {', '.join(MAP_MODES)}, got {mode!r}")
    return resolution, (coords[0], coords[1]), bool(negate), occ, free, mode


def _grey_and_alpha(img: Image.Image) -> tuple[np.ndarray, np.ndarray | None]:
    """Return the image's grey value (float, 0..255, mean of colour channels) and alpha (or ``None``)."""
    mode = img.mode
    if mode in ("P", "PA"):
        has_alpha = mode == "PA" or "transparency" in img.info
        img = img.convert("RGBA" if has_alpha else "RGB")
        mode = img.mode
    if mode == "1":
        return np.asarray(img.convert("L"), dtype=float), None
    if mode == "L":
        return np.asarray(img, dtype=float), None
    if mode in ("I;16", "I;16B", "I;16L", "I"):
        return np.asarray(img, dtype=float) / 257.0, None
    if mode in ("LA", "RGB", "RGBA"):
        arr = np.asarray(img, dtype=float)
        n_colour = {"LA": 1, "RGB": 3, "RGBA": 3}[mode]
        grey = arr[..., :n_colour].mean(axis=-1)
        alpha = arr[..., -1] if mode in ("LA", "RGBA") else None
        return grey, alpha
    raise MapError(
        "map.image", f"unsupported image mode '{img.mode}'; save it as 8-bit grey, palette, RGB(A) or 1-bit"
    )


def image_occupancy(
    img: Image.Image,
    *,
    negate: bool = False,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
    mode: str = "trinary",
) -> np.ndarray:
    """Classify an image's pixels into ``FREE``/``OCCUPIED``/``UNKNOWN`` by the ``map_server`` rules.

    Args:
        img: A Pillow image (see the module docstring for the supported modes).
        negate: Swap black and white (``negate: 1``).
        occupied_thresh: Occupancy probability above which a pixel is occupied.
        free_thresh: Occupancy probability below which a pixel is free.
        mode: ``trinary``, ``scale`` or ``raw``.

    Returns:
        ``int8`` array of the image's shape, **flipped** so that row 0 is the bottom of the picture.
    """
    grey, alpha = _grey_and_alpha(img)
    if mode == "raw":
        value = np.rint(255.0 - grey if negate else grey)
        in_range = value <= 100.0
        p = value / 100.0
    else:
        p = grey / 255.0 if negate else (255.0 - grey) / 255.0
        in_range = np.ones(p.shape, dtype=bool)
    cells = np.full(p.shape, UNKNOWN, dtype=np.int8)
    cells[in_range & (p > occupied_thresh)] = OCCUPIED
    cells[in_range & (p < free_thresh)] = FREE
    if alpha is not None:
        cells[alpha == 0] = UNKNOWN
    return np.ascontiguousarray(cells[::-1])


def _check_size(path: Path, img: Image.Image, resolution: float, origin: tuple[float, float]) -> None:
    """Refuse, from the image's header alone, a map that overflows the world or the memory available."""
    w, h = img.size
    for axis, start, cells in (("x", origin[0], w), ("y", origin[1], h)):
        if abs(start + cells * resolution) > MAX_COORDINATE_M:
            raise MapError("map.origin", f"the map's far edge in {axis} ({cells} pixels of {resolution:g} m from "
                                         f"{start:g} m) is more than {MAX_COORDINATE_M:g} m from the world origin; "
                                         "move the origin or use a coarser resolution")
    bands = 4 if img.mode in ("P", "PA") else len(img.getbands())
    need = w * h * (limits.BYTES_PER_IMAGE_BAND * bands + limits.BYTES_PER_IMAGE_PIXEL)
    limits.check_memory(need, "map.image", f"decoding '{path.name}' ({w} x {h} pixels, {img.mode})",
                        "use a smaller image (a coarser resolution)", error=MapError)


def _open_image(path: Path, resolution: float, origin: tuple[float, float]) -> Image.Image:
    """Open an image file, check its size from its header, decode it; every failure is a ``MapError``."""
    if not path.is_file():
        raise MapError(
            "map.image", f"image file '{path}' not found; the path is relative to the YAML file's folder"
        )
    try:
        with warnings.catch_warnings():  # the size is checked below, against this machine's memory
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            img = Image.open(path)
        try:
            _check_size(path, img, resolution, origin)
            img.load()
        except BaseException:
            img.close()
            raise
    except MapError:
        raise
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError, Image.DecompressionBombError) as exc:
        raise MapError(
            "map.image", f"'{path}' is not a readable image ({_one_line(exc)}); give a PGM or PNG file"
        ) from None
    if img.width == 0 or img.height == 0:
        raise MapError("map.image", f"'{path}' has no pixels; give a non-empty image")
    return img


def load_map_yaml(path: str | os.PathLike[str]) -> OccupancyMap:
    """Load a ROS ``map_server`` map (YAML file plus image) into an :class:`OccupancyMap`.

    Args:
        path: Path of the YAML file.

    Returns:
        The map; its ``name`` is the YAML file's stem, ``source`` the YAML path and ``licence`` the
        optional ``licence`` key.

    Raises:
        MapError: The YAML file or image is missing, unreadable or holds invalid values; the error's
            field names the key (``map``, ``map.image``, ``map.resolution``, ``map.origin``, ...).
    """
    path = Path(path)
    data = _read_yaml(path)
    resolution, origin, negate, occ, free, mode = _parse_params(data)

    image = data["image"]
    if not isinstance(image, str) or not image.strip():
        raise MapError("map.image", f"must be an image file name, got {image!r}")
    image_path = Path(image)
    if not image_path.is_absolute():
        image_path = path.parent / image_path
    img = _open_image(image_path, resolution, origin)

    licence = data.get("licence")
    if licence is not None and not isinstance(licence, str):
        raise MapError("map.licence", f"must be a string, got {licence!r}; quote it")

    cells = image_occupancy(img, negate=negate, occupied_thresh=occ, free_thresh=free, mode=mode)
    return OccupancyMap(
        name=path.stem,
        resolution=resolution,
        origin=origin,
        cells=cells,
        source=str(path),
        licence=licence,
    )
