"""Deployment algorithms, one module each, registered by name."""

from amronet.algorithms.base import ALGORITHMS, Command, Controller, Readings, StepInput, register_algorithm
from amronet.algorithms import self_spreading  # noqa: F401  (registers itself)

__all__ = ["ALGORITHMS", "Command", "Controller", "Readings", "StepInput", "register_algorithm"]
