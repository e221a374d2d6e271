"""Overrides: ``--set key=value`` items and dotted paths applied to a scenario's plain data."""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

from amronet.errors import ScenarioError
from amronet.yaml_loading import load_yaml

if TYPE_CHECKING:
    from amronet.engine.radio import RadioMedium

__all__ = ["apply_overrides", "parse_override"]


def parse_override(text: str) -> tuple[str, Any]:
    """Parse one ``--set key=value`` item; the value is YAML (``1e-3``, ``off``, ``[1, 2]``; :func:`load_yaml`).

    The value is read as a scenario file's values are: ``off``, ``on``, ``yes`` and ``no`` are words (the fields
    that take a boolean accept them), only ``true`` / ``false`` are booleans, ``010`` is ten.
    """
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ScenarioError("--set", f"expected KEY=VALUE such as radio.r_c=1.5, got {_shown(text)}")
    return key.strip(), load_yaml(value, key.strip(), f"value {_shown(value)}")


def _shown(text: str, most: int = 60) -> str:
    """``text`` quoted for a message, cut to its first ``most`` characters when longer (one short line)."""
    return repr(text) if len(text) <= most else f"{text[:most]!r}... ({len(text)} characters)"


def _radio_model(name: Any) -> type[RadioMedium] | None:
    """The radio model class registered as ``name``, or ``None``.

    The registry is imported here, only when an override names a radio model: it brings numba and scipy, which
    reading ``--set`` items or refusing a scenario file that does not exist should not wait for.
    """
    if not isinstance(name, str):
        return None
    from amronet.engine.radio import MEDIA

    return MEDIA.get(name)


def apply_overrides(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of ``data`` with dotted paths set (list items by index: ``base_stations.0.x``).

    One rule for every caller (``run --set``, sweeps, the library): an ``algorithm.name`` that switches to another
    algorithm drops the base's ``algorithm.params`` first, since they belong to the base's algorithm; the new one
    starts from its defaults and ``algorithm.params[.KEY]`` given in ``overrides`` apply on top. The same for the
    radio: ``radio.threshold_dbm`` given without ``radio.r_c`` replaces the base's ``r_c`` (and the other way round),
    and a ``radio.model`` that switches drops the base's ``wall_db`` / ``shadowing_db`` that the new model does not
    take.
    """
    out = copy.deepcopy(data)
    radio = out.get("radio") if isinstance(out, dict) else None
    if isinstance(radio, dict) and not isinstance(overrides.get("radio"), dict):
        for given, replaced in (("threshold_dbm", "r_c"), ("r_c", "threshold_dbm")):
            if f"radio.{given}" in overrides and f"radio.{replaced}" not in overrides:
                radio.pop(replaced, None)
        new_model = _radio_model(overrides.get("radio.model"))
        if new_model is not None and overrides["radio.model"] != radio.get("model"):
            for key, taken in (("wall_db", new_model.uses_walls), ("shadowing_db", new_model.uses_shadowing)):
                if not taken and f"radio.{key}" not in overrides:
                    radio.pop(key, None)
    algorithm = out.get("algorithm") if isinstance(out, dict) else None
    name = overrides.get("algorithm.name")
    if (isinstance(algorithm, dict) and name is not None and name != algorithm.get("name")
            and not isinstance(overrides.get("algorithm"), dict)):
        algorithm.pop("params", None)
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node: Any = out
        for i, part in enumerate(parts):
            last = i == len(parts) - 1
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ScenarioError(".".join(parts[: i + 1]), f"no list item {part}; the list has {len(node)}")
                key: Any = int(part)
            elif isinstance(node, dict):
                key = part
            else:
                raise ScenarioError(".".join(parts[:i]), "is not a mapping; cannot set a field inside it")
            if last:
                node[key] = value
            else:
                if isinstance(node, dict) and key not in node:
                    node[key] = {}
                node = node[key]
    return out
