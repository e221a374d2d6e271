"""The one YAML reader of scenario files, sweep files, map files and ``--set`` values.

PyYAML reads YAML 1.1, whose plain words and numbers surprise: ``off``, ``no`` and ``on`` are booleans (so
``coverage_target: off`` arrived as ``False``), ``2024-05-01`` is a date, ``1e-9`` and ``1E5`` are strings (a float
needs a dot and a signed exponent), ``010`` is the octal 8 and ``1:30`` the sexagesimal 90. It also keeps the last
of a key given twice, silently, and recurses once per level of nesting. :func:`load_yaml` reads YAML with the safe
loader but with YAML 1.2's core schema instead, and these rules:

* **Only** ``true`` / ``false`` (also ``True``, ``TRUE``, ``False``, ``FALSE``) **are booleans**, and ``null``,
  ``Null``, ``NULL``, ``~`` and an empty value are null. Every other plain word is a string: ``off``, ``on``,
  ``yes``, ``no``, ``y``, ``n``, ``none``, ``2024-05-01``. So a field whose values are words takes them as written
  (``sim.coverage_target: off``, ``algorithm.params.triangular: off`` or ``none``), and a field that takes a
  boolean (``radio.packet_loss``, ``sim.stop_when_settled``, a map's ``negate``...) takes ``true`` / ``false`` and
  also the words ``yes`` / ``no``, ``on`` / ``off`` and ``y`` / ``n`` in any case (:func:`as_bool`; the pydantic
  type is :data:`amronet.yaml_fields.YamlBool`), but no number. A field that takes text refuses a boolean or a
  number, saying to put the value in quotes (``name: '2024'``).
* **Numbers are YAML 1.2's**, plus ``_`` between digits as in Python: an integer is decimal digits
  with an optional sign (``42``, ``-3``, ``1_000``; a leading zero changes nothing, ``010`` is ten), or ``0x1F``
  (hexadecimal), or ``0o17`` (octal). A float has a dot or an exponent: ``1.5``, ``.5``, ``-2.5e+3``, ``1e-9``,
  ``1E5``, ``1e300``, ``5.``; ``.inf``, ``-.inf`` and ``.nan`` are infinity and not-a-number (fields that need a
  finite value refuse them, as before). YAML 1.1's binary (``0b101``) and sexagesimal (``1:30``) forms are strings,
  which a numeric field refuses.
* **A key given twice in one mapping is an error** naming the key and both lines.
* **Nesting is at most** :data:`MAX_DEPTH` **levels** of lists and mappings, aliases included (no amronet file needs
  more than ten), and an alias may not stand inside the node it names. Deeper input is refused while it is read,
  so neither the reader nor what checks and hashes its result afterwards (pydantic, ``copy.deepcopy``, JSON)
  recurses without bound.
* Input that PyYAML cannot turn into values (``!!float abc``, an integer of thousands of digits) is invalid YAML,
  not a crash.

Every failure is a :class:`~amronet.errors.ScenarioError` (or the subclass the caller names, e.g.
:class:`~amronet.errors.MapError`) of one line.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.error import MarkedYAMLError
from yaml.events import AliasEvent, MappingStartEvent, SequenceStartEvent
from yaml.nodes import CollectionNode, MappingNode, Node, ScalarNode, SequenceNode

from amronet.errors import ScenarioError

__all__ = ["BOOL_WORDS", "MAX_DEPTH", "DuplicateKeyError", "NestingError", "as_bool", "load_yaml"]

MAX_DEPTH = 100
"""The most levels of lists and mappings inside one another that a YAML document may nest (aliases included)."""

BOOL_WORDS: dict[str, bool] = {"true": True, "false": False, "yes": True, "no": False, "on": True, "off": False,
                               "y": True, "n": False}
"""The words a field that takes a boolean accepts besides ``true`` / ``false``, in any case (:func:`as_bool`)."""

_BOOL_TAG = "tag:yaml.org,2002:bool"
_NULL_TAG = "tag:yaml.org,2002:null"
_INT_TAG = "tag:yaml.org,2002:int"
_FLOAT_TAG = "tag:yaml.org,2002:float"
_MERGE_TAG = "tag:yaml.org,2002:merge"
_DIGITS = r"[0-9](?:_?[0-9])*"
_EXPONENT = r"[eE][-+]?[0-9]+"
_INT = re.compile(rf"^(?:[-+]?{_DIGITS}|0x[0-9a-fA-F]+|0o[0-7]+)$")
_FLOAT = re.compile(
    rf"^(?:[-+]?(?:{_DIGITS}\.(?:{_DIGITS})?(?:{_EXPONENT})?|\.{_DIGITS}(?:{_EXPONENT})?|{_DIGITS}{_EXPONENT})"
    r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
)
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")


def as_bool(value: Any) -> Any:
    """``value`` as a boolean if it is one or one of :data:`BOOL_WORDS` (any case); anything else unchanged.

    The words YAML 1.1 read as booleans (``yes``, ``off``...) are strings in YAML 1.2 (the module docstring); a field
    that takes a boolean turns them into one with this, and refuses what it returns unchanged (a number too).
    """
    if isinstance(value, str):
        return BOOL_WORDS.get(value.lower(), value)
    return value


class DuplicateKeyError(ConstructorError):
    """A mapping gives the same key twice.

    Args:
        key: The key.
        first: Where it is given first.
        second: Where it is given again.
    """

    def __init__(self, key: Any, first: yaml.Mark, second: yaml.Mark) -> None:
        super().__init__(None, None, f"key {key!r} appears twice", second)
        self.key, self.first, self.second = key, first, second

    def where(self) -> str:
        """Both places, 1-based: ``lines 3 and 9``, or ``line 1, columns 2 and 10`` in one line."""
        a, b = self.first, self.second
        if a.line != b.line:
            return f"lines {a.line + 1} and {b.line + 1}"
        return f"line {a.line + 1}, columns {a.column + 1} and {b.column + 1}"


class NestingError(MarkedYAMLError):
    """Lists and mappings nest deeper than :data:`MAX_DEPTH` levels, or an alias stands inside the node it names.

    Args:
        problem: What is wrong, in a few words.
        mark: Where the offending node starts.
        advice: How to fix it, in a few words.
    """

    def __init__(self, problem: str, mark: yaml.Mark, advice: str = "flatten it") -> None:
        super().__init__(problem=problem, problem_mark=mark)
        self.advice = advice


class _Loader(yaml.SafeLoader):
    """The safe loader with YAML 1.2's core schema, duplicate keys and deep nesting refused (the module docstring)."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._open = 0
        """Lists and mappings being composed around the current node."""
        self._heights: dict[int, int] = {}
        """Levels of nesting of each list or mapping composed so far, by ``id`` (aliases share their node)."""

    def compose_node(self, parent: Node | None, index: Any) -> Node:
        """Compose a node; more than :data:`MAX_DEPTH` levels, or an alias inside its own node, raise NestingError.

        PyYAML composes a few Python calls deeper per level: the count stops it long before the interpreter's recursion
        limit. An alias adds its node's own levels where it stands, so a chain of aliases cannot nest deeper either.
        """
        if not self.check_event(SequenceStartEvent, MappingStartEvent):
            if self.check_event(AliasEvent):
                anchor = self.peek_event().anchor
                node = self.anchors.get(anchor)
                if isinstance(node, CollectionNode) and id(node) not in self._heights:
                    raise NestingError(f"alias *{anchor} stands inside the node it names", self.peek_event().start_mark,
                                      "name another node")
            return super().compose_node(parent, index)
        mark = self.peek_event().start_mark
        if self._open >= MAX_DEPTH:
            raise NestingError(f"lists and mappings nested deeper than {MAX_DEPTH} levels", mark)
        self._open += 1
        try:
            node = super().compose_node(parent, index)
        finally:
            self._open -= 1
        inner = node.value if isinstance(node, SequenceNode) else [n for pair in node.value for n in pair]
        height = 1 + max((self._heights.get(id(n), 0) for n in inner), default=0)
        if height > MAX_DEPTH:
            raise NestingError(f"through aliases, lists and mappings nested deeper than {MAX_DEPTH} levels", mark)
        self._heights[id(node)] = height
        return node

    def construct_mapping(self, node: MappingNode, deep: bool = False) -> dict[Any, Any]:
        """Construct a mapping; a key given twice (merge keys ``<<`` aside) raises :class:`DuplicateKeyError`."""
        if isinstance(node, MappingNode):
            seen: dict[Any, yaml.Mark] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.setdefault(key, key_node.start_mark)
                except TypeError:  # an unhashable key: the safe loader's own error follows
                    continue
                if first is not key_node.start_mark:
                    raise DuplicateKeyError(key, first, key_node.start_mark)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node: ScalarNode) -> int:
        """An integer (decimal, ``0x`` hexadecimal or ``0o`` octal; ``_`` between digits)."""
        text = str(self.construct_scalar(node))
        if not _INT.match(text):
            raise ConstructorError(None, None, f"{text!r} is not an integer", node.start_mark)
        if text[:2] in ("0x", "0o"):
            return int(text[2:], 16 if text[1] == "x" else 8)
        try:
            return int(text.replace("_", ""), 10)
        except ValueError:  # more digits than Python converts
            raise ConstructorError(None, None, f"an integer of {len(text)} digits is too long",
                                   node.start_mark) from None

    def construct_yaml_float(self, node: ScalarNode) -> float:
        """A float (``1.5``, ``.5``, ``1e-9``, ``-2.5E+3``, ``.inf``, ``.nan``; ``_`` between digits)."""
        text = str(self.construct_scalar(node))
        if not _FLOAT.match(text) and not _INT.match(text):
            raise ConstructorError(None, None, f"{text!r} is not a number", node.start_mark)
        lowered = text.replace("_", "").lower()
        if lowered.lstrip("+-") in (".inf", ".nan"):
            return float(lowered.replace(".", ""))
        return float(int(lowered, 0)) if lowered[:2] in ("0x", "0o") else float(lowered)


_Loader.yaml_implicit_resolvers = {  # YAML 1.2's core schema: null from PyYAML, then bool, int and float below
    first: kept for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
    if (kept := [(tag, regexp) for tag, regexp in resolvers if tag in (_NULL_TAG, _MERGE_TAG)])
}
_Loader.add_implicit_resolver(_BOOL_TAG, _BOOL, list("tTfF"))
_Loader.add_implicit_resolver(_INT_TAG, _INT, list("-+0123456789"))
_Loader.add_implicit_resolver(_FLOAT_TAG, _FLOAT, list("-+0123456789."))
_Loader.add_constructor(_INT_TAG, _Loader.construct_yaml_int)
_Loader.add_constructor(_FLOAT_TAG, _Loader.construct_yaml_float)


def load_yaml(text: str | bytes, field: str, source: str = "", *,
              error: type[ScenarioError] = ScenarioError) -> Any:
    """Read a YAML document with amronet's rules (the module docstring): YAML 1.2's core schema, no key twice.

    Args:
        text: The document.
        field: The field that errors name: ``scenario``, ``sweep``, ``map``, the key of a ``--set`` value.
        source: What the text is, for the messages, e.g. ``'sweep.yaml'`` or ``value '{r_c: 1'``; empty: nothing.
        error: The class of the error raised (:class:`~amronet.errors.MapError` for a map file).

    Returns:
        The document's value (``None`` for an empty document).

    Raises:
        ScenarioError: A key given twice (``key 'radio' appears twice in 'my.yaml' (lines 3 and 9); keep one``),
            nesting too deep (``... is not valid YAML at line 1 (lists and mappings nested deeper than 100
            levels); flatten it``), or text that is not valid YAML (``... is not valid YAML at line 3; fix the
            syntax``); of class ``error``.
    """
    subject = f"{source} is not" if source else "not"
    try:
        return yaml.load(text, Loader=_Loader)  # _Loader is a SafeLoader: no arbitrary objects
    except DuplicateKeyError as exc:
        inside = f" in {source}" if source else ""
        raise error(field, f"key {exc.key!r} appears twice{inside} ({exc.where()}); keep one") from None
    except NestingError as exc:
        line = exc.problem_mark.line + 1 if exc.problem_mark is not None else 1
        raise error(field, f"{subject} valid YAML at line {line} ({exc.problem}); {exc.advice}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        reason = f" ({exc.problem})" if isinstance(exc, ConstructorError) and exc.problem else ""
    except (ValueError, OverflowError, RecursionError) as exc:  # what PyYAML's constructors let through
        where, reason = "", f" ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
    raise error(field, f"{subject} valid YAML{where}{reason}; fix the syntax")
