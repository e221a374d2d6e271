"""Pictures: maps to scale and deployment snapshots (Agg backend, no pyplot state)."""

from amronet.viz.snapshot import (
    KINDS,
    MAP_COLOURS,
    NO_SHADING,
    STATES,
    Nodes,
    Shading,
    draw_map,
    save_map_picture,
    save_snapshot,
    snapshot_figure,
)

__all__ = [
    "KINDS",
    "MAP_COLOURS",
    "NO_SHADING",
    "STATES",
    "Nodes",
    "Shading",
    "draw_map",
    "save_map_picture",
    "save_snapshot",
    "snapshot_figure",
]
