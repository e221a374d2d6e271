"""What amronet knows of each deployment algorithm without importing its controller (and its compiled kernels).

An algorithm package's ``__init__.py`` declares its algorithm with :func:`declare`: the name, the module that
defines and registers its controller, its parameters' model and what its scenarios default to. Declaring is light
(pydantic, no NumPy, no numba), so a scenario is validated -- and a bad one refused -- without the kernels;
:data:`ALGORITHMS` imports an algorithm's controller module the first time its controller is looked up::

    # amronet/algorithms/my_algo/__init__.py
    from amronet.algorithms.declaration import declare
    from amronet.algorithms.my_algo.params import MyAlgoParams

    declare("my-algo", controller="amronet.algorithms.my_algo.controller", params=MyAlgoParams)

    # amronet/algorithms/my_algo/controller.py
    @ALGORITHMS.register("my-algo")
    class MyAlgo(Controller):
        Params = MyAlgoParams
        ...
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from amronet.registry import Registry

if TYPE_CHECKING:
    from amronet.algorithms.base import Controller

__all__ = ["ALGORITHMS", "DECLARATIONS", "Declaration", "declaration_of", "declare"]


@dataclass(frozen=True)
class Declaration:
    """An algorithm as its scenarios know it.

    Attributes:
        name: The registry name (``algorithm.name``).
        controller: The module that defines the controller and registers it in :data:`ALGORITHMS`.
        params: The model of ``algorithm.params`` (unknown parameters are errors); the controller's ``Params``.
        scenario_defaults: Scenario fields (``section.field``) that take these values when a scenario of this
            algorithm leaves them out, instead of the schema's defaults (:mod:`amronet.scenario.defaults`).
        follows_paths: Whether the controller drives agents along given paths (``agents.trajectories``,
            :attr:`~amronet.algorithms.base.Setup.paths`).
    """

    name: str
    controller: str
    params: type[BaseModel]
    scenario_defaults: Mapping[str, Any]
    follows_paths: bool


ALGORITHMS: Registry[type[Controller]] = Registry("algorithm")
"""Deployment algorithms' controllers by name: every declared name is known at once, and a controller registers
itself with ``@ALGORITHMS.register(name)`` when its module is imported (on first lookup)."""

DECLARATIONS: Registry[Declaration] = Registry("algorithm")
"""Every algorithm's :class:`Declaration`, by name (the same names as :data:`ALGORITHMS`)."""


def declare(name: str, *, controller: str, params: type[BaseModel], scenario_defaults: Mapping[str, Any] | None = None,
            follows_paths: bool = False) -> Declaration:
    """Declare an algorithm (see :class:`Declaration` for the arguments); called by its package's ``__init__``."""
    declaration = Declaration(name, controller, params, MappingProxyType(dict(scenario_defaults or {})),
                              follows_paths)
    DECLARATIONS.add(name, declaration)
    ALGORITHMS.declare(name, controller)
    return declaration


def declaration_of(name: str) -> Declaration:
    """The declaration of the algorithm ``name`` (one of :data:`ALGORITHMS`), without importing its controller.

    A controller registered without a declaration (by code that defined and imported it, e.g. a test's) is declared
    by its class: its ``Params`` and, if it has them, its ``scenario_defaults`` and ``follows_paths``.

    Raises:
        KeyError: No algorithm has that name.
    """
    if name in DECLARATIONS:
        return DECLARATIONS[name]
    cls = ALGORITHMS[name]
    return Declaration(name, cls.__module__, cls.Params, MappingProxyType(dict(getattr(cls, "scenario_defaults", {}))),
                       bool(getattr(cls, "follows_paths", False)))
