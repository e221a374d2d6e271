"""Where numba keeps amronet's compiled kernels: one cache per version of the kernels' source.

numba's own cache (``cache=True``) checks only the timestamp of the file that holds a kernel. A kernel whose
*callee* in another file changed (``count_walls`` in ``walls.py``, called from ``hearing.py``), or a constant it
reads from another module, would load its old machine code and compute with code that is no longer there. So
unless the user chose a cache folder (``NUMBA_CACHE_DIR``), amronet keeps its kernels in a folder named by a hash
of the source of every module that holds kernels and of every amronet module they import, directly or not:
``$XDG_CACHE_HOME/amronet/numba-HASH`` (``~/.cache/...`` without ``XDG_CACHE_HOME``). A change to any of them
starts a fresh cache, which the next run (or ``amronet compile``) fills; a change elsewhere (the command line,
the experiments, the pictures) keeps it. The folders of the :data:`KEEP` most recently used versions are kept,
older ones removed -- but only folders amronet made: a folder is removed when it carries amronet's stamp
(:data:`STAMP`, holding the folder's own hash) *and* holds nothing but what amronet and numba write there (the
stamp, the warm-up notes, numba's index and data files). A folder named like amronet's that the user made, or one
of amronet's into which the user put a file of their own, is never touched. A relative ``XDG_CACHE_HOME`` is
ignored, as the XDG Base Directory specification asks. Where no such folder can be written, numba's default
(``__pycache__`` next to the sources) applies.

numba has one cache setting per process, so a program that imports amronet and then defines kernels of its own
with ``cache=True`` finds their cache in the same folder (still correct: numba checks their own source files;
they are compiled again when a new amronet version starts a new folder). Set ``NUMBA_CACHE_DIR`` to keep them
elsewhere.

A kernel that calls another with a constant (``f(x, True)``, ``g(a, 1)``) makes numba compile the callee once more
for that literal value, a copy of seconds each: kernels pass ``np.bool_(True)``, ``np.int64(1)`` instead, which
share the version the Python callers use (``tests/test_warmup.py`` finds any literal version left).

A warm-up (:mod:`amronet.sim.warmup`) that finished leaves a note in the folder (``compiled-all``,
``compiled-common``): a sweep on a cold cache compiles the common kernels across its workers first, and only then.

A cache entry that cannot be loaded (an empty, truncated or garbled index or data file) is recompiled, never
fatal (:mod:`amronet.kernel_cache_repair`, installed by :func:`configure`); :func:`clear` (``amronet compile
--fresh``) empties the folder of the kernels' present source. Processes that share the folder (``amronet
compile``'s workers, a sweep's) compile each kernel once between them: the others wait and load it
(:mod:`amronet.kernel_cache_lock`, its lock files in ``locks/``).

:func:`configure` must run before the first kernel is defined: :mod:`amronet.numba_setup` (installed by
``amronet/__init__.py``) calls it as soon as numba is imported.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
from pathlib import Path

__all__ = ["KEEP", "STAMP", "cache_folder", "clear", "compiled", "configure", "mark_compiled"]

KEEP = 8
"""Cache folders of this many source versions are kept (most recently used first)."""

STAMP = "amronet-kernel-cache"
"""The file that marks a cache folder as amronet's; it holds the folder's name (``numba-HASH``)."""

_FOLDER_NAME = re.compile(r"^numba-[0-9a-f]{16}$")
_OURS = re.compile(r"^(?:compiled-[\w-]+|.+\.nb[ic](?:\.tmp\.[\w-]+)?|.+\.lock)$")
"""Files amronet or numba write in a cache folder: the warm-up notes, numba's index and data files (and the
temporary files numba writes them through), the locks of kernels being compiled (:mod:`amronet.kernel_cache_lock`)."""

_PACKAGE = Path(__file__).resolve().parent
_KERNEL = re.compile(r"^@(numba\.)?njit\b", re.MULTILINE)
"""A module holds kernels when a line starts with a numba decorator."""

_folder: Path | None = None
"""The folder :func:`configure` pointed numba at (``None``: the user's ``NUMBA_CACHE_DIR``, or numba's default)."""
_locks: Path | None = None
"""The folder whose ``locks`` hold the kernels' compile locks (:mod:`amronet.kernel_cache_lock`): :data:`_folder`, or
``amronet`` in the user's ``NUMBA_CACHE_DIR``."""

_IMPORT = re.compile(r"^\s*(?:from|import) (amronet(?:\.\w+)*)", re.MULTILINE)


def _module_file(name: str) -> Path | None:
    path = _PACKAGE.joinpath(*name.split(".")[1:])
    for candidate in (path.with_suffix(".py"), path / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _kernel_sources() -> list[Path]:
    """The modules that hold kernels and every amronet module they import, directly or not.

    numba compiles the constants a kernel reads from other modules (state codes, cell values) into its machine
    code, so a change to any of them must start a fresh cache too.
    """
    found = {p for p in _PACKAGE.rglob("*.py") if _KERNEL.search(p.read_text(encoding="utf-8"))}
    todo = list(found)
    while todo:
        for name in _IMPORT.findall(todo.pop().read_text(encoding="utf-8")):
            path = _module_file(name)
            if path is not None and path not in found:
                found.add(path)
                todo.append(path)
    return sorted(found)


def _cache_home() -> Path:
    """``$XDG_CACHE_HOME``, or ``~/.cache`` where it is unset, empty or relative (the XDG specification)."""
    home = os.environ.get("XDG_CACHE_HOME", "")
    return Path(home) if os.path.isabs(home) else Path.home() / ".cache"


def cache_folder(root: Path | None = None) -> Path:
    """The cache folder of the kernels' present source, under ``root`` (default: the user's cache folder)."""
    if root is None:
        root = _cache_home() / "amronet"
    digest = hashlib.sha256()
    for path in _kernel_sources():
        digest.update(path.relative_to(_PACKAGE).as_posix().encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return root / f"numba-{digest.hexdigest()[:16]}"


def _stamp(folder: Path) -> None:
    """Mark ``folder`` as amronet's cache folder (:data:`STAMP`), if it is not yet."""
    stamp = folder / STAMP
    if not stamp.is_file():
        stamp.write_text(folder.name + "\n", encoding="utf-8")


def _removable(folder: Path) -> bool:
    """Whether ``folder`` is one amronet made and holds nothing but what amronet and numba wrote there.

    Not a symbolic link, named ``numba-HASH``, stamped with its own name, and every file in it (at any depth) a
    warm-up note or one of numba's cache files; no symbolic link inside.
    """
    if folder.is_symlink() or not folder.is_dir() or not _FOLDER_NAME.match(folder.name):
        return False
    try:
        if (folder / STAMP).read_text(encoding="utf-8").strip() != folder.name:
            return False
        for path in folder.rglob("*"):
            if path.is_symlink():
                return False
            if path.is_file() and path.parent == folder and path.name == STAMP:
                continue
            if not path.is_dir() and not _OURS.match(path.name):
                return False
    except (OSError, UnicodeDecodeError):
        return False
    return True


def _prune(folder: Path) -> None:
    """Remove amronet's cache folders of all but the :data:`KEEP` most recently used source versions.

    Only folders :func:`_removable` accepts count and go: nothing the user made or put there is removed.
    """
    ours = [p for p in folder.parent.iterdir() if p != folder and _removable(p)]
    ours.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    for old in ours[KEEP - 1:]:
        shutil.rmtree(old, ignore_errors=True)


def configure() -> Path | None:
    """Point numba's cache at :func:`cache_folder` unless ``NUMBA_CACHE_DIR`` is set; return the folder used.

    ``None``: the user's ``NUMBA_CACHE_DIR`` applies, or no folder could be written (numba's default applies).
    Whichever folder applies, an entry that cannot be loaded is recompiled (:mod:`amronet.kernel_cache_repair`);
    in amronet's folder and in the user's ``NUMBA_CACHE_DIR``, processes compile each kernel once between them
    (:mod:`amronet.kernel_cache_lock`; there its locks are in a folder ``amronet``).
    """
    global _folder, _locks
    from amronet import kernel_cache_lock, kernel_cache_repair

    kernel_cache_repair.install(lambda: _folder)
    kernel_cache_lock.install(lambda: _locks)
    _folder = _locks = None
    mine = os.environ.get("NUMBA_CACHE_DIR")
    if mine:  # numba caches there; the locks go there too, made as the first kernel compiles
        _locks = Path(mine) / "amronet"
        return None
    try:
        folder = cache_folder()
        folder.mkdir(parents=True, exist_ok=True)
        _stamp(folder)
        os.utime(folder)  # used now: the pruning keeps the most recently used versions
        _prune(folder)
    except OSError:
        return None
    if not os.access(folder, os.W_OK):
        return None
    import numba

    numba.config.CACHE_DIR = str(folder)
    _folder = _locks = folder
    return folder


def mark_compiled(name: str) -> None:
    """Note in the cache folder that the warm-up ``name`` finished (:mod:`amronet.sim.warmup`).

    Its kernels are cached. Nothing is noted where amronet does not manage the folder.
    """
    if _folder is not None:
        with contextlib.suppress(OSError):
            (_folder / f"compiled-{name}").touch()


def compiled(*names: str) -> bool | None:
    """Whether one of the warm-ups ``names`` finished with this version of the kernels (:func:`mark_compiled`).

    ``None``: unknown, amronet does not manage the cache folder (the user's ``NUMBA_CACHE_DIR``, or none writable).
    """
    if _folder is None:
        return None
    return any((_folder / f"compiled-{name}").is_file() for name in names)


_COMPILED = re.compile(r"^(?:compiled-[\w-]+|.+\.nb[ic])$")
"""The files :func:`clear` removes: the warm-up notes and numba's index and data files (not the temporary files
numba writes them through: another process may be writing one)."""


def clear() -> int | None:
    """Remove the compiled kernels and warm-up notes from amronet's cache folder; return how many files went.

    Only the warm-up notes and numba's ``.nbi`` and ``.nbc`` files in the folder :func:`configure` chose go
    (regular files, not symbolic links; the folder and its stamp stay): the next run, or ``amronet compile``,
    compiles every kernel afresh. ``None``: amronet does not manage the folder (the user's ``NUMBA_CACHE_DIR``, or
    none writable), and removes nothing.
    """
    if _folder is None:
        return None
    removed = 0
    for parent, _dirs, files in os.walk(_folder):  # does not descend into symbolic links
        for name in files:
            path = Path(parent) / name
            if _COMPILED.match(name) and not path.is_symlink() and path.is_file():
                with contextlib.suppress(FileNotFoundError):
                    path.unlink()
                    removed += 1
    return removed
