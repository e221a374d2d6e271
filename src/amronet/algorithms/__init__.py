"""Deployment algorithms, one module each, registered by name."""

from amronet.algorithms import (  # noqa: F401  (register themselves)
    agent_assisted,
    dssa,
    potential_field,
    self_spreading,
)
from amronet.algorithms.base import ALGORITHMS, Command, Controller, Readings, StepInput, register_algorithm

__all__ = ["ALGORITHMS", "Command", "Controller", "Readings", "StepInput", "register_algorithm"]
