"""One registry helper for everything amronet looks up by name: algorithms, radio models, explorers, figures.

A :class:`Registry` maps names to objects (usually classes). Modules register what they define with the
:meth:`Registry.register` decorator; :meth:`Registry.lookup` turns an unknown name into one line that names the
field and the known choices::

    MEDIA = Registry("radio model")

    @MEDIA.register("unit-disk")
    class UnitDisk(RadioMedium): ...

    MEDIA.lookup(name, field="radio.model")   # ScenarioError: radio.model: unknown radio model 'x'; choose ...

A registry also reads like a read-only mapping (``name in REG``, ``REG[name]``, ``list(REG)``, ``len(REG)``).

A name can be *declared* before its object exists: ``REG.declare("x", "pkg.module")`` makes ``x`` known at once
(``"x" in REG``, ``list(REG)``, an unknown name's message) and imports ``pkg.module``, which registers it, the first
time its object is asked for. So a registry of classes whose modules are heavy (compiled kernels) answers which
names exist without importing them (:mod:`amronet.algorithms.declaration`).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator, Mapping
from typing import Generic, TypeVar

from amronet.errors import ScenarioError

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(Mapping[str, T], Generic[T]):
    """Objects registered by name.

    Args:
        what: What the registry holds, in words, for error messages (e.g. ``"radio model"``).
    """

    def __init__(self, what: str) -> None:
        self.what = what
        self._items: dict[str, T] = {}
        self._modules: dict[str, str] = {}
        """Declared names and the modules that register them (:meth:`declare`), in the order declared."""

    def register(self, name: str) -> Callable[[T], T]:
        """Decorator that registers its target under ``name`` (and sets the target's ``name`` if it is a class).

        Raises:
            ValueError: ``name`` is taken already (two modules would otherwise silently shadow each other).
        """

        def deco(obj: T) -> T:
            if name in self._items and self._items[name] is not obj:
                raise ValueError(f"{self.what} {name!r} is registered twice")
            if isinstance(obj, type):
                obj.name = name  # type: ignore[attr-defined]
            self._items[name] = obj
            return obj

        return deco

    def declare(self, name: str, module: str) -> None:
        """Make ``name`` known now; its object is registered by ``module``, imported when the object is first used.

        Raises:
            ValueError: ``name`` is declared with another module already.
        """
        if self._modules.get(name, module) != module:
            raise ValueError(f"{self.what} {name!r} is declared twice")
        self._modules[name] = module

    def add(self, name: str, obj: T) -> T:
        """Register ``obj`` under ``name`` (the function form of :meth:`register`)."""
        return self.register(name)(obj)

    def lookup(self, name: str, field: str) -> T:
        """The object registered under ``name``.

        Raises:
            ScenarioError: ``name`` is unknown; the message names ``field`` and the known names.
        """
        try:
            return self[name]
        except (KeyError, TypeError):
            raise ScenarioError(field, f"unknown {self.what} {name!r}; choose one of: {', '.join(sorted(self))}"
                                ) from None

    def __getitem__(self, name: str) -> T:
        if name not in self._items and name in self._modules:
            importlib.import_module(self._modules[name])
            if name not in self._items:
                raise LookupError(f"{self._modules[name]} did not register the {self.what} {name!r} it declares")
        return self._items[name]

    def __contains__(self, name: object) -> bool:
        try:
            return name in self._items or name in self._modules
        except TypeError:  # unhashable
            return False

    def __iter__(self) -> Iterator[str]:
        return iter([*self._modules, *(name for name in self._items if name not in self._modules)])

    def __len__(self) -> int:
        return len(self._modules.keys() | self._items.keys())

    def __repr__(self) -> str:
        return f"Registry({self.what!r}: {', '.join(self)})"
