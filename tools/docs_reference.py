"""The documentation's generated reference pages: every scenario key, and every command-line option.

The scenario reference is read from the pydantic models that validate a scenario (their fields, types, defaults and
bounds) and from their docstrings (attribute docstrings, or a Google ``Attributes:`` section; a field a model does not
describe takes its base class's description), so it cannot drift from what the code accepts. The command-line
reference is read from ``amronet``'s own argparse parser.

``mkdocs build`` runs this module through the ``gen-files`` plugin (``mkdocs.yml``); the tests import it to check
that every field and every command appears.
"""

from __future__ import annotations

import argparse
import re
import types
import typing
from collections.abc import Iterator
from typing import Any, Literal

import annotated_types as at
import griffe
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

__all__ = ["cli_reference", "scenario_reference", "write_pages"]

_SECTIONS = ("algorithm", "radio", "base_stations", "routers", "agents", "sim", "faults")


# --------------------------------------------------------------------------------------------- descriptions


def _descriptions(cls: type[BaseModel]) -> dict[str, str]:
    """Each field's description: its attribute docstring, else its entry in an ``Attributes:`` section.

    A field a class does not describe takes the description of the nearest base class that does (``VORParams``
    says nothing of the fields it inherits from ``HoleParams``), so a description is written once, where the field
    is.
    """
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):  # the farthest base first: nearer classes override
        if isinstance(klass, type) and issubclass(klass, BaseModel) and klass is not BaseModel:
            out.update(_own_descriptions(klass))
    return {k: _one_paragraph(v) for k, v in out.items() if k in cls.model_fields}


def _own_descriptions(cls: type[BaseModel]) -> dict[str, str]:
    """The descriptions ``cls``'s own docstrings give: its ``Attributes:`` section, then its attribute docstrings."""
    try:
        obj = griffe.load(cls.__module__, resolve_aliases=False)[cls.__qualname__]
    except (KeyError, griffe.GriffeError, ModuleNotFoundError):  # pragma: no cover - a model defined elsewhere
        return {}
    out: dict[str, str] = {}
    if obj.docstring is not None:
        for section in obj.docstring.parse("google", warnings=False):
            if section.kind.value == "attributes":
                out.update({a.name: a.description for a in section.value})
    for name, member in obj.members.items():
        doc = getattr(member, "docstring", None)
        if doc is not None and name in cls.model_fields:
            out[name] = doc.value
    return out


def _one_paragraph(text: str) -> str:
    """A docstring as one Markdown table cell: reST roles and double backquotes made Markdown, lines joined."""
    text = re.sub(r":(?:mod|class|func|meth|data|attr):`~?([^`]+)`", r"`\1`", text)
    text = text.replace("``", "`")
    return " ".join(line.strip() for line in text.splitlines() if line.strip()).replace("|", "\\|")


# ------------------------------------------------------------------------------------------------- types


def _type_text(annotation: Any) -> str:
    """An annotation in words a scenario author reads: ``number``, ``integer``, ``true/false``, ``one of a, b``."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        return _type_text(args[0])
    if origin in (typing.Union, types.UnionType):
        parts = [_type_text(a) for a in args if a is not type(None)]
        text = " or ".join(dict.fromkeys(parts))
        return text + (" or null" if type(None) in args else "")
    if origin is Literal:
        return "one of " + ", ".join(f"`{a}`" for a in args)
    if origin in (list, tuple):
        inner = [a for a in args if a is not Ellipsis]
        if origin is tuple and len(inner) > 1:
            return "[" + ", ".join(_type_text(a) for a in inner) + "]"
        return "list of " + (_type_text(inner[0]) if inner else "values")
    if origin is dict:
        return "mapping"
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return "mapping"
    names = {bool: "true/false", int: "integer", float: "number", str: "text", typing.Any: "any"}
    return names.get(annotation, getattr(annotation, "__name__", str(annotation)))


def _bounds(info: FieldInfo) -> str:
    """The field's numeric and length bounds, from its metadata and that of its annotation (``> 0``, ``1 .. 360``)."""
    metadata = list(info.metadata)
    stack = [info.annotation]
    while stack:
        ann = stack.pop()
        if typing.get_origin(ann) is typing.Annotated:
            base, *extra = typing.get_args(ann)
            metadata.extend(m for m in extra if not isinstance(m, FieldInfo))
            for m in extra:
                if isinstance(m, FieldInfo):
                    metadata.extend(m.metadata)
            stack.append(base)
        elif typing.get_origin(ann) in (typing.Union, types.UnionType):
            stack.extend(typing.get_args(ann))
    words = []
    for m in metadata:
        for attr, sign in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤")):
            if isinstance(m, getattr(at, attr.capitalize())):
                words.append(f"{sign} {getattr(m, attr):g}")
        if isinstance(m, at.MinLen):
            words.append(f"at least {m.min_length} long")
        if isinstance(m, at.MaxLen):
            words.append(f"at most {m.max_length} long")
    return ", ".join(dict.fromkeys(words))


def _default_text(info: FieldInfo) -> str:
    if info.is_required():
        return "required"
    if info.default_factory is not None:
        value = info.default_factory()
        if isinstance(value, BaseModel):
            return "see below"
        return f"`{value!r}`" if value not in ({}, []) else ("none" if value == [] else "`{}`")
    value = info.default
    if value is PydanticUndefined:
        return "required"
    if value is None:
        return "`null`"
    if isinstance(value, bool):
        return f"`{str(value).lower()}`"
    if isinstance(value, tuple):
        return "`[" + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value) + "]`"
    if isinstance(value, float):
        return f"`{value:g}`"
    return f"`{value}`"


def field_rows(cls: type[BaseModel], prefix: str) -> Iterator[tuple[str, str, str, str, str]]:
    """One row per field of ``cls``: key (dotted, under ``prefix``), type, default, bounds, description."""
    described = _descriptions(cls)
    for name, info in cls.model_fields.items():
        if info.exclude:
            continue
        key = f"{prefix}.{name}" if prefix else name
        yield (f"`{key}`", _type_text(info.annotation), _default_text(info), _bounds(info), described.get(name, ""))


def _table(rows: Iterator[tuple[str, ...]]) -> list[str]:
    lines = ["| key | type | default | bounds | meaning |", "|---|---|---|---|---|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return lines


def _class_doc(cls: type) -> str:
    doc = (cls.__doc__ or "").strip().split("\n\n")[0]
    return _one_paragraph(doc)


# -------------------------------------------------------------------------------------------- the scenario


def scenario_reference() -> str:
    """The scenario reference page, in Markdown."""
    from amronet.algorithms import ALGORITHMS
    from amronet.algorithms.agent_assisted.drops import DROP_RULES
    from amronet.algorithms.agent_assisted.explorers import EXPLORERS
    from amronet.engine.radio import MEDIA
    from amronet.engine.robots import ROBOT_MODELS
    from amronet.scenario.schema import RobotSpec, Scenario
    from amronet.sweeps.spec import SweepSpec

    out = ["# Scenario reference", "",
           "Generated from the models that validate a scenario (`amronet.scenario.schema` and each algorithm's",
           "parameters): every key, its type, its default and its bounds. A key left out takes its default; an",
           "unknown key, a wrong type or a value out of bounds is refused with one line naming the key.", "",
           "## Top level", ""]
    out += _table(field_rows(Scenario, ""))
    for section in _SECTIONS:
        info = Scenario.model_fields[section]
        model = _model_in(info.annotation)
        if model is None:
            continue
        out += ["", f"## `{section}`", "", _class_doc(model), ""]
        prefix = f"{section}[i]" if section in ("base_stations", "faults") else section
        out += _table(field_rows(model, prefix))
        if section == "algorithm":
            out += ["", "`algorithm.name` is one of " + ", ".join(f"`{n}`" for n in ALGORITHMS) + "; "
                    "`algorithm.params` are the chosen algorithm's parameters, below."]
        if section == "radio":
            out += ["", "`radio.model` is one of " + ", ".join(f"`{n}`" for n in MEDIA) + "."]
    out += ["", "## Robot models", "",
            "`routers.robot`, `agents.robot` and `base_stations[i].robot` take a name or a mapping of four fields.", "",
            "| name | radius (m) | max speed (m/s) | sensor beams | sensor range (m) |", "|---|---|---|---|---|"]
    out += [f"| `{r.name}` | {r.radius:g} | {r.max_speed:g} | {r.sensor_beams} | {r.sensor_range:g} |"
            for r in ROBOT_MODELS.values()]
    out += [""]
    out += _table(field_rows(RobotSpec, "robot"))
    for name, cls in ALGORITHMS.items():
        out += ["", f"## `algorithm.params` of `{name}`", "", _class_doc(cls.Params), ""]
        out += _table(field_rows(cls.Params, "algorithm.params"))
    out += ["", "## Explorers (`algorithm.params.explorer`)", ""]
    out += [f"- `{name}`: {_class_doc(cls)}" for name, cls in EXPLORERS.items()]
    out += ["", "## Drop rules (`algorithm.params.drop_rule`)", ""]
    for name, rule in DROP_RULES.items():
        out += [f"### `{name}`", "", _class_doc(rule), ""]
        params = getattr(rule, "Params", None)
        if params is not None and params.model_fields:
            out += _table(field_rows(params, "algorithm.params.drop"))
            out += [""]
    out += ["", "## Sweep files", "", _class_doc(SweepSpec), ""]
    out += _table(field_rows(SweepSpec, ""))
    return "\n".join(out) + "\n"


def _model_in(annotation: Any) -> type[BaseModel] | None:
    """The pydantic model a field holds (directly, or as the items of its list)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


# ------------------------------------------------------------------------------------------ the command line


def _subcommands(parser: argparse.ArgumentParser) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield name, sub
                for deeper, subsub in _subcommands(sub):
                    yield f"{name} {deeper}", subsub


def _help_of(parser: argparse.ArgumentParser, name: str) -> str:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                if choice.dest == name.split()[-1]:
                    return choice.help or ""
    return ""


def cli_reference() -> str:
    """The command-line reference page, in Markdown (from ``amronet``'s argparse parser)."""
    from amronet.cli.main import build_parser

    parser = build_parser()
    out = ["# Command-line reference", "",
           "Generated from `amronet`'s own parser (`amronet COMMAND --help` prints the same). Every error a user",
           "can cause prints one line `amronet: error: ...` and exits with status 2; nothing is written then.", ""]
    parents = {"": parser}
    for name, sub in _subcommands(parser):
        parent = parents[" ".join(name.split()[:-1])]
        parents[name] = sub
        depth = "##" if " " not in name else "###"
        out += [f"{depth} `amronet {name}`", ""]
        text = sub.description or _help_of(parent, name)
        if text:
            out += [text[0].upper() + text[1:], ""]
        usage = sub.format_usage().replace("usage: ", "").strip()
        out += ["```", usage, "```", ""]
        rows = []
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
                continue
            flags = ", ".join(f"`{o}`" for o in action.option_strings) or f"`{action.dest}`"
            default = "" if action.default in (None, False, argparse.SUPPRESS) or action.required else \
                f" (default `{action.default}`)"
            choices = f" One of {', '.join(f'`{c}`' for c in action.choices)}." if action.choices else ""
            helptext = (action.help or "").replace("%(default)s", str(action.default)).replace("|", "\\|")
            rows.append(f"| {flags} | {helptext}{choices}{default} |")
        if rows:
            out += ["| option | meaning |", "|---|---|", *rows, ""]
    return "\n".join(out) + "\n"


def write_pages() -> None:
    """Write both pages into the documentation being built (``mkdocs-gen-files``)."""
    import mkdocs_gen_files

    with mkdocs_gen_files.open("reference/scenario.md", "w") as f:
        f.write(scenario_reference())
    with mkdocs_gen_files.open("reference/cli.md", "w") as f:
        f.write(cli_reference())


if __name__ in ("__main__", "<run_path>"):
    write_pages()
