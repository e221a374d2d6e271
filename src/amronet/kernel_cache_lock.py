"""Processes that share amronet's kernel cache compile each kernel once between them, not each for itself.

numba compiles a kernel on its first call in a process, unless it finds the kernel in its on-disk cache. Two
processes that start on a cold cache at once (``amronet compile``'s workers, a sweep's) both miss, so both
compile the same kernels, each as slowly as one alone: ``amronet compile``'s two workers spent a third of their
time compiling what the other was compiling.

:func:`install` (called by :func:`amronet.kernel_cache.configure`) wraps numba's ``Dispatcher.compile`` so that,
in the cache folder amronet manages, a process takes an exclusive lock on a file named by the kernel and its
signature (``locks/<kernel>-<line>.<hash>.lock``) before it looks the kernel up in the cache, and keeps it while it
compiles and saves it. A second process that needs the same kernel waits for the lock and then loads what the
first one saved. A kernel's callees are locked inside their caller's lock: calls between kernels form no cycle, so
no two processes wait for each other. The lock is ``flock``'s, which the system releases when its process ends,
however it ends; a process that waited :data:`PATIENCE` seconds compiles by itself, as numba alone would (a
missing lock makes nothing wrong, it only makes work twice). In the user's ``NUMBA_CACHE_DIR`` (a CI's, a
container's) the locks are in a folder of amronet's own there, ``amronet/locks``; where numba's default
``__pycache__`` applies (amronet's folder cannot be written), or without ``fcntl``, nothing is locked.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

__all__ = ["PATIENCE", "install", "lock_path"]

PATIENCE = 300.0
"""Seconds a process waits for another one's lock on a kernel before it compiles the kernel itself."""

_POLL = 0.02
"""Seconds between two tries of a lock another process holds."""

_installed = False


def _no_folder() -> Path | None:
    return None


_managed_folder: Callable[[], Path | None] = _no_folder
"""The folder amronet manages now (given by :func:`install`), or ``None``."""
_held: set[Path] = set()
"""The lock files this process holds (numba compiles under its own process-wide lock: one thread at a time)."""


def lock_path(dispatcher: Any, args: tuple[Any, ...]) -> Path | None:
    """The lock file of a kernel and its argument types, or ``None`` where nothing is locked.

    ``folder/locks/<numba's index file name without .nbi>.<hash>.lock`` in the folder that keeps them; the hash is of
    the index file's path (two modules of one name in two packages differ by their folder only) and the types.

    Args:
        dispatcher: The kernel (numba's dispatcher, ``cache=True``).
        args: The argument types it compiles for (numba types).
    """
    folder = _managed_folder()
    cache = getattr(dispatcher, "_cache", None)
    index = getattr(getattr(cache, "_cache_file", None), "_index_path", None)
    if folder is None or index is None:  # not cached on disk (cache=False), or numba's default folder
        return None
    digest = hashlib.sha256(f"{index}\0{tuple(args)}".encode()).hexdigest()[:16]
    return folder / "locks" / f"{os.path.basename(index).removesuffix('.nbi')}.{digest}.lock"


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """Hold the ``flock`` of ``path``; wait for it at most :data:`PATIENCE` seconds, then go on without it."""
    import fcntl

    if path in _held:  # numba compiling the same kernel again inside itself: this process holds it already
        yield
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield  # a folder that cannot be written: compile unlocked, as numba alone does
        return
    try:
        deadline = time.monotonic() + PATIENCE
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:  # another process holds it
                if time.monotonic() >= deadline:
                    break  # go on unlocked: the work is done twice, nothing is wrong
                time.sleep(_POLL)
            except OSError:  # a file system without locks
                break
        _held.add(path)
        try:
            yield
        finally:
            _held.discard(path)
    finally:
        os.close(fd)  # releases the lock


def _wrap_compile(original: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
    from numba.core import sigutils
    from numba.core.compiler_lock import global_compiler_lock

    def compile(self: Any, sig: Any) -> Any:
        with global_compiler_lock:  # numba's own, taken first: the same order as numba's compile
            args, _ = sigutils.normalize_signature(sig)
            path = None if tuple(args) in self.overloads else lock_path(self, args)
            if path is None:
                return original(self, sig)
            with _locked(path):
                return original(self, sig)

    compile.__doc__ = original.__doc__
    return compile


def install(managed_folder: Callable[[], Path | None]) -> None:
    """Lock each kernel's compiling across processes (see the module's docstring); idempotent.

    Args:
        managed_folder: The folder that keeps the locks at the time of a compile (``None``: none; nothing is
            locked), :func:`amronet.kernel_cache.configure`'s.
    """
    global _installed, _managed_folder
    _managed_folder = managed_folder
    if _installed:
        return
    try:
        import fcntl  # noqa: F401 (POSIX only: elsewhere numba compiles unlocked)
    except ImportError:
        return
    from numba.core.dispatcher import Dispatcher

    Dispatcher.compile = _wrap_compile(Dispatcher.compile)
    _installed = True
