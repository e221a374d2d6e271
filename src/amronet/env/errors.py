"""The environments' errors: a bad argument, a missing optional extra (one line each, like every amronet error)."""

from __future__ import annotations

from amronet.errors import AmronetError

__all__ = ["EnvError", "MissingExtraError"]


class EnvError(AmronetError, ValueError):
    """An environment's argument or an action is invalid.

    Args:
        field: The offending argument, e.g. ``max_steps`` or ``actions[agent_0]``.
        message: What is wrong and how to fix it, in one line.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}")

    def __reduce__(self) -> tuple[type, tuple[str, str]]:
        return type(self), (self.field, self.message)


class MissingExtraError(AmronetError, ImportError):
    """:mod:`amronet.env` is used without its optional dependencies (the extra ``rl``)."""
