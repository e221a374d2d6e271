"""One line per invalid scenario: pydantic's first error turned into the field's dotted path and a message.

A validator that knows better says it itself as ``@field.path@message`` (a ``ValueError``); other errors are
worded here: an unknown key lists the keys allowed where it stands, a missing one says so, a wrong value shows
what was given (and, where YAML read a boolean or a number for a text field, says to quote it:
:mod:`amronet.yaml_loading`).
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel, ValidationError

from amronet.errors import ScenarioError

__all__ = ["to_scenario_error"]

_UNION_TAGS = ("name", "spec")
"""The tags of :data:`~amronet.scenario.schema.RobotRef`'s two forms: pydantic puts them into an error's location
after ``robot``."""


def _field_path(loc: tuple[Any, ...], prefix: str = "") -> str:
    path = prefix
    for k, part in enumerate(loc):
        if isinstance(part, int):
            path += f"[{part}]"
        elif not (part in _UNION_TAGS and k > 0 and loc[k - 1] == "robot"):
            path += ("." if path else "") + str(part)
    return path


def _allowed_keys(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    current: Any = model
    for k, part in enumerate(loc[:-1]):
        if isinstance(part, int) or (part in _UNION_TAGS and k > 0 and loc[k - 1] == "robot"):
            continue
        field = getattr(current, "model_fields", {}).get(part)
        if field is None:
            return []
        found = _model_in(field.annotation)
        if found is not None:
            current = found
    return [k for k in getattr(current, "model_fields", {}) if k != "base_dir"]


def _model_in(annotation: Any, depth: int = 0) -> type[BaseModel] | None:
    """The first pydantic model inside an annotation (through unions, ``Annotated`` and containers)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    if depth > 4:
        return None
    for inner in getattr(annotation, "__args__", ()) or ():
        found = _model_in(inner, depth + 1)
        if found is not None:
            return found
    origin = getattr(annotation, "__origin__", None)
    return _model_in(origin, depth + 1) if origin is not None and origin is not annotation else None


def to_scenario_error(exc: ValidationError, *, model: type[BaseModel], prefix: str = "") -> ScenarioError:
    """The first error of a pydantic validation as one :class:`~amronet.errors.ScenarioError` naming the field.

    Args:
        exc: What pydantic raised.
        model: The model validated (a scenario, a sweep file, an algorithm's parameters): an unknown key's error
            lists the keys allowed where it stands.
        prefix: Dotted path of the validated data inside the scenario (``algorithm.params``), put before the field.

    Returns:
        The error to raise.
    """
    err = exc.errors()[0]
    msg = str(err.get("msg", "invalid"))
    if msg.startswith("Value error, @"):
        _, field, text = msg.split("@", 2)
        return ScenarioError(field, text)
    loc = tuple(err.get("loc", ()))
    field = _field_path(loc, prefix)
    if err.get("type") == "extra_forbidden":
        allowed = _allowed_keys(model, loc)
        return ScenarioError(field, "unknown key; allowed keys here: " + ", ".join(allowed))
    if err.get("type") == "missing":
        return ScenarioError(field, "required field is missing; add it")
    got = err.get("input")
    shown = repr(got) if not isinstance(got, dict | list) else type(got).__name__
    if isinstance(got, float) and math.isnan(got):
        shown = "nan"
    if err.get("type") == "model_type":  # a section given a plain value: name the keys it takes, not the class
        keys = ", ".join(_allowed_keys(model, (*loc, None)))
        return ScenarioError(field, f"must be a mapping of its fields (got {shown}); its keys: {keys}")
    hint = ""
    if err.get("type") == "string_type" and isinstance(got, bool | int | float):
        hint = f"; YAML read a {'boolean' if isinstance(got, bool) else 'number'}: put the value in quotes"
    elif err.get("type") == "bool_type":
        hint = "; give true or false (or yes / no, on / off)"
    return ScenarioError(field, f"{msg[0].lower()}{msg[1:]} (got {shown}){hint}")
