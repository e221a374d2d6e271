"""Whether the optional extra ``rl`` (PettingZoo, Gymnasium) is installed; :mod:`amronet.env` needs it."""

from __future__ import annotations

import importlib.util

from amronet.env.errors import MissingExtraError

__all__ = ["require_extra"]

PACKAGES = ("pettingzoo", "gymnasium")


def require_extra() -> None:
    """Raise :class:`MissingExtraError` (one line) unless PettingZoo and Gymnasium can be imported."""
    missing = [name for name in PACKAGES if importlib.util.find_spec(name) is None]
    if missing:
        raise MissingExtraError(f"amronet.env needs {' and '.join(missing)} (the optional extra 'rl'): "
                                "pip install 'amronet[rl]'")
