"""Naming a sweep point by its values (``r_c=2.5, triangular=local``) instead of its scenario hash.

The store keeps, for every run of a sweep, the point's labels: the swept keys and their values
(``{"radio.r_c": 2.5, "algorithm.params.triangular": "local"}``), or a figure's labels (``r_c``, ``agents``...).
Tables show the keys that vary, each by the last component of its dotted path when no other shown key ends the
same way (``radio.r_c`` → ``r_c``), else by as many components as it takes to tell them apart.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

__all__ = ["point_text", "short_keys", "value_text", "varied_keys"]


def short_keys(keys: Sequence[str]) -> dict[str, str]:
    """Key → its shortest trailing part of whole path components that no other key of ``keys`` ends with.

    A part starting with a list index is widened by one component (``base_stations.0.x``, not ``0.x``).

    Examples:
        >>> short_keys(["radio.r_c", "algorithm.params.triangular"])
        {'radio.r_c': 'r_c', 'algorithm.params.triangular': 'triangular'}
        >>> short_keys(["agents.robot.max_speed", "routers.robot.max_speed"])
        {'agents.robot.max_speed': 'agents.robot.max_speed', 'routers.robot.max_speed': 'routers.robot.max_speed'}
    """
    out = {}
    for key in keys:
        parts = key.split(".")
        for n in range(1, len(parts) + 1):
            tail = parts[-n:]
            if tail[0].isdigit() and n < len(parts):
                continue
            text = ".".join(tail)
            if not any(other != key and (other == text or other.endswith("." + text)) for other in keys):
                break
        out[key] = text
    return out


def varied_keys(labels: Iterable[Mapping[str, Any]]) -> list[str]:
    """The keys whose value is not the same in every one of ``labels`` (given in point order), outer keys first.

    A key missing from some labels varies. The store keeps labels with sorted keys, so the grid's order is read
    back from the points' order: the key whose value changes least often from one labels to the next comes first
    (a grid's outer key), ties in order of first appearance. When none varies (one point), every key is returned.
    """
    sets = list(labels)
    keys = list(dict.fromkeys(k for lab in sets for k in lab))
    values = {k: [json.dumps(lab[k], sort_keys=True) if k in lab else "\0" for lab in sets] for k in keys}
    varied = [k for k in keys if len(set(values[k])) > 1]
    changes = {k: sum(a != b for a, b in zip(values[k], values[k][1:], strict=False)) for k in varied}
    return sorted(varied, key=lambda k: changes[k]) or keys


def value_text(value: Any) -> str:
    """A label value as text: floats as Python writes them (``0.8``, ``1e-05``), lists and mappings as JSON."""
    if isinstance(value, dict | list):
        return json.dumps(value, separators=(",", ":"))
    return "" if value is None else str(value)


def point_text(labels: Mapping[str, Any], short: Mapping[str, str]) -> str:
    """``"r_c=2.5, triangular=local"``: the labels among ``short``'s keys, by their short names, in its order."""
    return ", ".join(f"{name}={value_text(labels[key])}" for key, name in short.items() if key in labels)
