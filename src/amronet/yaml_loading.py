"""The one YAML reader of scenario files, sweep files and ``--set`` values.

PyYAML reads YAML 1.1, whose numbers surprise: ``1e-9`` and ``1E5`` are strings (a float needs a dot and a signed
exponent), ``010`` is the octal 8 and ``1:30`` the sexagesimal 90. It also keeps the last of a key given twice,
silently. :func:`load_yaml` reads YAML with the safe loader but with these rules instead:

* **Numbers are YAML 1.2's** (its core schema), plus ``_`` between digits as in Python: an integer is decimal digits
  with an optional sign (``42``, ``-3``, ``1_000``; a leading zero changes nothing, ``010`` is ten), or ``0x1F``
  (hexadecimal), or ``0o17`` (octal). A float has a dot or an exponent: ``1.5``, ``.5``, ``-2.5e+3``, ``1e-9``,
  ``1E5``, ``1e300``, ``5.``; ``.inf``, ``-.inf`` and ``.nan`` are infinity and not-a-number (fields that need a
  finite value refuse them, as before). YAML 1.1's binary (``0b101``) and sexagesimal (``1:30``) forms are strings,
  which a numeric field refuses.
* **A key given twice in one mapping is an error** naming the key and both lines.
* Input that PyYAML cannot turn into values (a date that does not exist, ``!!float abc``, an integer of thousands
  of digits, nesting too deep) is invalid YAML, not a crash.

Every failure is a :class:`~amronet.errors.ScenarioError` of one line.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.nodes import MappingNode, ScalarNode

from amronet.errors import ScenarioError

__all__ = ["DuplicateKeyError", "load_yaml"]

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


class _Loader(yaml.SafeLoader):
    """The safe loader with YAML 1.2's numbers and duplicate keys refused (see the module docstring)."""

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


_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag not in (_INT_TAG, _FLOAT_TAG)]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Loader.add_implicit_resolver(_INT_TAG, _INT, list("-+0123456789"))
_Loader.add_implicit_resolver(_FLOAT_TAG, _FLOAT, list("-+0123456789."))
_Loader.add_constructor(_INT_TAG, _Loader.construct_yaml_int)
_Loader.add_constructor(_FLOAT_TAG, _Loader.construct_yaml_float)


def load_yaml(text: str | bytes, field: str, source: str = "") -> Any:
    """Read a YAML document with amronet's rules (the module docstring): YAML 1.2's numbers, no key twice.

    Args:
        text: The document.
        field: The field that errors name: ``scenario``, ``sweep``, the key of a ``--set`` value.
        source: What the text is, for the messages, e.g. ``'sweep.yaml'`` or ``value '{r_c: 1'``; empty: nothing.

    Returns:
        The document's value (``None`` for an empty document).

    Raises:
        ScenarioError: A key given twice (``key 'radio' appears twice in 'my.yaml' (lines 3 and 9); keep one``), or
            text that is not valid YAML (``... is not valid YAML at line 3; fix the syntax``).
    """
    try:
        return yaml.load(text, Loader=_Loader)  # _Loader is a SafeLoader: no arbitrary objects
    except DuplicateKeyError as exc:
        inside = f" in {source}" if source else ""
        raise ScenarioError(field, f"key {exc.key!r} appears twice{inside} ({exc.where()}); keep one") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        reason = f" ({exc.problem})" if isinstance(exc, ConstructorError) and exc.problem else ""
    except (ValueError, OverflowError, RecursionError) as exc:  # what PyYAML's constructors let through
        where, reason = "", f" ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
    subject = f"{source} is not" if source else "not"
    raise ScenarioError(field, f"{subject} valid YAML{where}{reason}; fix the syntax")
