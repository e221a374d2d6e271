"""Typed exceptions of amronet.

Every error a user can cause carries one line that names the offending field and says how to fix it.
The command line prints that line and exits with status 2; the library raises the exception.
"""

from __future__ import annotations

__all__ = ["AmronetError", "MapError", "RecordingError", "ScenarioError"]


class AmronetError(Exception):
    """Base class of every error amronet raises on bad input."""


class ScenarioError(AmronetError, ValueError):
    """A scenario (file, preset, dict or override) is invalid.

    Args:
        field: Dotted path of the offending field, e.g. ``radio.r_c``.
        message: What is wrong and how to fix it, in one line.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        self.message = message
        super().__init__(f"{field}: {message}" if field else message)

    def __reduce__(self) -> tuple[type, tuple[str, str]]:
        return type(self), (self.field, self.message)


class MapError(ScenarioError):
    """A map file or image cannot be loaded or makes no sense."""


class RecordingError(AmronetError):
    """A recording (``recording.npz``) is damaged, truncated or forged: one of its arrays cannot be what it claims.

    Args:
        path: The file, as the message names it.
        field: The offending array (``xy_quantum``, ``status``), ``meta`` or a key of it (``meta.r_c``), or
            ``file`` when the file as a whole cannot be read.
        problem: What is wrong with it, in a few words.
    """

    def __init__(self, path: str, field: str, problem: str) -> None:
        self.path = path
        self.field = field
        self.problem = problem
        super().__init__(f"{path} is damaged or was not written by amronet run --record ({problem}); "
                         "record the run again")

    def __reduce__(self) -> tuple[type, tuple[str, str, str]]:
        return type(self), (self.path, self.field, self.problem)
