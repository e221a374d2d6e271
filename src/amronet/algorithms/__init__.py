"""Deployment algorithms, one module each, registered by name."""

from amronet.algorithms import agent_assisted, self_spreading  # noqa: F401  (register themselves)
from amronet.algorithms.base import ALGORITHMS, Command, Controller, Readings, StepInput, register_algorithm

__all__ = ["ALGORITHMS", "Command", "Controller", "Readings", "StepInput", "register_algorithm"]
