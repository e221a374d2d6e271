"""Set numba up for amronet the moment numba is imported, and not before: ``import amronet`` stays light.

amronet points numba's cache at its own folder (:func:`amronet.kernel_cache.configure`) and asks for a fork-safe
thread pool (:func:`amronet.threads.configure`). Both must happen before the first kernel is defined (numba picks a
kernel's cache folder when its decorator runs), but importing numba costs about half a second, which the command
line's ``--help`` or a refused scenario should not pay. So :func:`install` (called by ``amronet/__init__.py``) does
both at once if numba is imported already, and otherwise leaves a finder on :data:`sys.meta_path` that does them
right after numba's own import finishes -- whoever imports it, an amronet module with kernels or the user's code.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

__all__ = ["install"]


def _configure() -> None:
    # imported here: amronet.threads imports numba, which is what this module waits for
    from amronet import kernel_cache, threads

    kernel_cache.configure()
    threads.configure()


class _AfterNumba(importlib.abc.MetaPathFinder):
    """Finds nothing itself: when numba is about to be imported, has :func:`_configure` run right after it."""

    def find_spec(self, fullname: str, path: Sequence[str] | None, target: ModuleType | None = None
                  ) -> ModuleSpec | None:
        if fullname != "numba":
            return None
        sys.meta_path.remove(self)  # once only; the other finders locate numba
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None or not hasattr(spec.loader, "exec_module"):
            return spec
        loader = spec.loader
        original = loader.exec_module

        def exec_module(module: ModuleType) -> None:
            del loader.exec_module  # the loader's own method again
            original(module)
            _configure()

        loader.exec_module = exec_module  # type: ignore[method-assign]
        return spec


def install() -> None:
    """Configure numba for amronet now if it is imported, else right after it is (see the module); idempotent."""
    if "numba" in sys.modules:
        _configure()
    elif not any(isinstance(finder, _AfterNumba) for finder in sys.meta_path):
        sys.meta_path.insert(0, _AfterNumba())
