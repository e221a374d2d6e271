"""Shared pieces of the paper-figure experiments: the agent-assisted scenario, output files, claim tables."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from amronet.outputs.files import write_files_atomically
from amronet.world.builtin import FLOOR_CORNERS

__all__ = ["STORE_FILES", "Claim", "agent_scenario", "claims_markdown", "csv_table_text", "csv_text", "load_plotting",
           "write_outputs"]

CORNERS = FLOOR_CORNERS
"""Base-station positions at the corners of the 32 m x 32 m floors (paper 5.1: 'located at the corner')."""
START_LOCATIONS = (*CORNERS, (16.0, 16.0))
"""Five start locations for Fig. 5: the four corners and the centre (a corridor crossing on office-32x32)."""


def agent_scenario(map_name: str, r_c: float, bases: tuple[tuple[float, float], ...], agents_per_base: int,
                   explorer: str, time_limit: float, dt: float = 0.25, *, radio: dict[str, Any] | None = None,
                   drop_rule: str | None = None, drop: dict[str, Any] | None = None,
                   agents: dict[str, Any] | None = None) -> dict[str, Any]:
    """The agent-assisted scenario of paper 5.1 as plain data.

    Args:
        map_name: The map.
        r_c: Communication radius (the median range under other radio models), metres.
        bases: Base-station positions.
        agents_per_base: Agents per base station.
        explorer: The agents' exploration strategy.
        time_limit: Simulated seconds at most.
        dt: Step length.
        radio: Further ``radio`` fields (e.g. ``{"model": "multi-wall", "shadowing_db": 4}``); default the unit disk.
        drop_rule: ``algorithm.params.drop_rule`` (default: left out, the paper's rule).
        drop: ``algorithm.params.drop``, the rule's parameters (default: left out).
        agents: Further ``agents`` fields (e.g. ``{"routers_carried": 12, "when_empty": "continue"}``).

    Left at their defaults the optional fields are not written, so the scenario (and its hash in a result store) is
    the one the figures have always used.
    """
    params: dict[str, Any] = {"triangular": "local", "explorer": explorer}
    if drop_rule is not None:
        params["drop_rule"] = drop_rule
    if drop:
        params["drop"] = dict(drop)
    return {
        "name": f"agent-assisted-{map_name}",
        "map": map_name,
        "algorithm": {"name": "agent-assisted", "params": params},
        "radio": {"model": "unit-disk", "r_c": float(r_c), **(radio or {})},
        "base_stations": [{"x": x, "y": y, "region": [1.6, 1.6]} for x, y in bases],
        "routers": {"count": 0, "robot": "bebot"},
        "agents": {"per_base": int(agents_per_base), "robot": "pioneer", **(agents or {})},
        "sim": {"dt": dt, "time_limit": float(time_limit), "record_every": 40, "coverage_target": 0.99},
    }


@dataclass(frozen=True)
class Claim:
    """One claim of the paper next to our measurement."""

    claim: str
    paper: str
    ours: str
    verdict: str


def claims_markdown(title: str, claims: list[Claim]) -> str:
    """A Markdown table of claims."""
    lines = [f"## {title}", "", "| claim (paper) | paper | amronet | verdict |", "|---|---|---|---|"]
    lines += [f"| {c.claim} | {c.paper} | {c.ours} | {c.verdict} |" for c in claims]
    return "\n".join(lines) + "\n"


def load_plotting() -> None:
    """Import matplotlib's figure and Agg canvas (most of a second the first time): work for while the runs go."""
    import matplotlib.backends.backend_agg
    import matplotlib.figure  # noqa: F401


def csv_text(rows: list[dict[str, Any]]) -> str:
    """Rows of dicts as CSV text (columns from the first row)."""
    return csv_table_text(list(rows[0]), (row.values() for row in rows)) if rows else ""


def csv_table_text(columns: Sequence[str], rows: Iterable[Iterable[Any]]) -> str:
    """A header and rows of values in that order as CSV text (a long table without a dict per row)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(rows)
    return buf.getvalue()


STORE_FILES = ("results.sqlite", "results.sqlite-wal")
"""The default result store of ``amronet reproduce`` (in the output folder), kept when the folder is replaced."""


def write_outputs(out_dir: Path, files: dict[str, bytes | str]) -> Path:
    """Write an experiment's files atomically as the content of ``out_dir`` (keeping its result store)."""
    return write_files_atomically(Path(out_dir), {k: v.encode() if isinstance(v, str) else v for k, v in files.items()},
                                  keep=STORE_FILES)
