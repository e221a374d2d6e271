"""Deployment algorithms, one package each, registered by name in :data:`ALGORITHMS`."""

from amronet.algorithms import (  # noqa: F401  (register themselves)
    agent_assisted,
    dssa,
    potential_field,
    self_spreading,
)
from amronet.algorithms.base import (
    ALGORITHMS,
    AreaKnowledge,
    Command,
    Controller,
    Readings,
    RouterStock,
    Setup,
    StepInput,
)

__all__ = ["ALGORITHMS", "AreaKnowledge", "Command", "Controller", "Readings", "RouterStock", "Setup", "StepInput"]
