"""The built-in maps' names, and whether a map reference is a name nobody knows -- light (no NumPy, no image reader).

A scenario is checked against these before anything heavy is imported, so ``map: nope`` is refused at once.
"""

from __future__ import annotations

import os
from pathlib import Path
from types import MappingProxyType

__all__ = ["BUILTIN_MAPS", "looks_like_path", "unknown_map_message"]

BUILTIN_MAPS: MappingProxyType[str, str] = MappingProxyType(
    {
        "open-6x6": "empty 6 m x 6 m arena centred on (0, 0), walls only at the edge",
        "obstacles-6x6": "6 m x 6 m arena, block and wall obstacles around a free centre (self-spreading)",
        "open-32x32": "empty 32 m x 32 m field, walls only at the edge",
        "office-32x32": "32 m x 32 m office floor: 2 m corridors, rooms behind 1-1.2 m doors, free corners",
        "autolab": "Stage autolab: rooms with doorways (real building, 1-bit image)",
        "cave": "Stage cave: open cave with thin outlines, the classic Stage demo world",
        "depot": "navigation2 depot: SLAM-style trinary map with shelves and pillars",
        "hospital_section": "Stage hospital section: many rooms and corridors, 1 px walls",
    }
)
"""Name → one-line description of every built-in map (the registry; its order is the listing order)."""


def looks_like_path(ref: str) -> bool:
    """Whether a map reference that is not a built-in name is taken as a file's path.

    It is when it ends in ``.yaml``/``.yml``, holds a path separator or names an existing file.
    """
    return (ref.lower().endswith((".yaml", ".yml")) or "/" in ref or os.sep in ref or Path(ref).is_file())


def unknown_map_message(ref: str) -> str | None:
    """The message refusing ``ref`` when it is neither a built-in name nor a path, else ``None``."""
    if ref in BUILTIN_MAPS or looks_like_path(ref):
        return None
    return (f"unknown map '{ref}'; use a built-in name (amronet maps list: {', '.join(BUILTIN_MAPS)}) "
            "or a path to a ROS map_server YAML")
