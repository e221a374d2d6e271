"""Deployment algorithms, one module each, registered by name."""

from amronet.algorithms import self_spreading  # noqa: F401  (registers itself)
from amronet.algorithms.base import ALGORITHMS, Command, Controller, Readings, StepInput, register_algorithm

__all__ = ["ALGORITHMS", "Command", "Controller", "Readings", "StepInput", "register_algorithm"]
