"""A damaged entry of numba's kernel cache is recompiled, never fatal.

numba loads a kernel's cache entry from two pickled files: the index ``<kernel>-<line>.pyXY.nbi`` (which data file
holds which signature) and the data ``<kernel>-<line>.pyXY.N.nbc`` (the machine code). numba writes them through a
temporary file, but a full disk, a copy cut short or a bad sector leaves one empty, truncated or garbled, and
numba lets the error of unpickling it (``EOFError``, ``UnpicklingError``, ``ValueError``, ...) end the program:
every run, and ``amronet compile`` itself, until the user deleted the cache by hand.

:func:`install` (called by :func:`amronet.kernel_cache.configure`) wraps three methods of ``numba.core.caching``
so that an entry that cannot be loaded is a miss, which numba compiles and saves afresh:

* ``IndexDataCacheFile._load_index``: an index that cannot be read or unpickled, or is not a mapping, counts as
  empty (numba's own answer for an index of another numba version or of an older source).
* ``IndexDataCacheFile._load_data``: a data file that cannot be unpickled counts as missing (numba's own answer
  for a data file removed under its index).
* ``Cache.load_overload``: any other error of loading (the machine code unpickled but cannot be rebuilt) counts
  as a miss too.

Where amronet manages the cache folder (:func:`amronet.kernel_cache.configure`), the damaged file -- the one
``.nbi`` or ``.nbc`` file that failed, nothing else -- is removed, and numba writes a sound one when it saves the
recompiled kernel. Where it does not (the user's ``NUMBA_CACHE_DIR``, or numba's default ``__pycache__``), amronet
removes nothing: numba itself overwrites the damaged index or data file when it saves the recompiled kernel under
the same name, as it overwrites a stale one (so a damaged entry numba wrote in the user's folder is replaced by a
sound one; no other file there is touched). Either way the first damaged entry a process meets prints one line on
stderr, naming the cache folder; later ones in the same process are repaired silently.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["install", "notice"]

_installed = False


def _no_folder() -> Path | None:
    return None


_managed_folder: Callable[[], Path | None] = _no_folder
"""The folder amronet manages now (given by :func:`install`), or ``None``."""
_notice: str | None = None
"""The line printed for the first damaged entry this process met (``None``: none met yet)."""


def notice() -> str | None:
    """The notice this process printed about a damaged cache entry, or ``None`` if it met none."""
    return _notice


def _managed(path: Path) -> Path | None:
    """The cache folder amronet manages if ``path`` is one of numba's index or data files in it, else ``None``.

    Only a regular ``.nbi`` or ``.nbc`` file (not a symbolic link) whose real path lies in the folder
    :func:`amronet.kernel_cache.configure` pointed numba at counts.
    """
    folder = _managed_folder()
    if folder is None or path.suffix not in (".nbi", ".nbc") or path.is_symlink() or not path.is_file():
        return None
    try:
        path.resolve().relative_to(folder.resolve())
    except (OSError, ValueError):
        return None
    return folder


def _discard(path: Path, exc: BaseException) -> None:
    """Remove the damaged cache file ``path`` if amronet manages its folder; say so once per process."""
    global _notice
    folder = _managed(path)
    if folder is not None:
        with contextlib.suppress(OSError):
            path.unlink()
    if _notice is not None:
        return
    why = f"{path.name}: {type(exc).__name__}"
    if folder is not None:
        _notice = (f"amronet: discarded damaged entries of the kernel cache in {folder} ({why}); "
                   "recompiling them")
    else:
        _notice = (f"amronet: damaged entries in the kernel cache {path.parent} ({why}); recompiling them, "
                   "numba overwrites them")
    print(_notice, file=sys.stderr, flush=True)


def _wrap_load_index(original: Callable[[Any], dict]) -> Callable[[Any], dict]:
    def _load_index(self: Any) -> dict:
        try:
            overloads = original(self)
            if not isinstance(overloads, dict):
                raise TypeError(f"the index holds a {type(overloads).__name__}, not a dict")
        except Exception as exc:  # whatever a damaged pickle raises, the index is unusable
            _discard(Path(self._index_path), exc)
            return {}
        return overloads

    _load_index.__doc__ = original.__doc__
    return _load_index


def _wrap_load_data(original: Callable[[Any, str], Any]) -> Callable[[Any, str], Any]:
    def _load_data(self: Any, name: str) -> Any:
        try:
            return original(self, name)
        except OSError:
            raise  # numba's load() takes it for a data file removed under its index: a miss
        except Exception as exc:  # whatever a damaged pickle raises, the entry is unusable
            _discard(Path(self._data_path(name)), exc)
            return None

    _load_data.__doc__ = original.__doc__
    return _load_data


def _wrap_load_overload(original: Callable[[Any, Any, Any], Any]) -> Callable[[Any, Any, Any], Any]:
    def load_overload(self: Any, sig: Any, target_context: Any) -> Any:
        try:
            return original(self, sig, target_context)
        except Exception as exc:  # the data unpickled but cannot be rebuilt: compile afresh
            name = None
            with contextlib.suppress(Exception):
                name = self._cache_file._load_index().get(self._index_key(sig, target_context.codegen()))
            if name is not None:
                _discard(Path(self._cache_file._data_path(name)), exc)
            else:
                _discard(Path(self._cache_file._index_path), exc)
            return None

    load_overload.__doc__ = original.__doc__
    return load_overload


def install(managed_folder: Callable[[], Path | None]) -> None:
    """Make numba treat a cache entry that cannot be loaded as a miss (see the module's docstring); idempotent.

    Args:
        managed_folder: The cache folder amronet manages at the time of a load (``None``: none; files are then
            never removed), :func:`amronet.kernel_cache.configure`'s.
    """
    global _installed, _managed_folder
    _managed_folder = managed_folder
    if _installed:
        return
    from numba.core import caching

    files = caching.IndexDataCacheFile
    files._load_index = _wrap_load_index(files._load_index)
    files._load_data = _wrap_load_data(files._load_data)
    caching.Cache.load_overload = _wrap_load_overload(caching.Cache.load_overload)
    _installed = True
