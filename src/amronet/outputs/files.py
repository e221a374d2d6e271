"""Writing output files and folders atomically, without ever touching what amronet did not write.

A folder amronet writes (``run --out``, ``reproduce``, ``plan --out``, ``results --export --out``) holds a small
manifest, :data:`MANIFEST`, that lists every file amronet put there with its SHA-256. A folder may be replaced
only when it is absent, empty, or holds nothing but the files its manifest lists, unchanged, and the files the
command keeps (a result store). Anything else — a file of the user's, a subfolder, a file edited since amronet
wrote it, a folder an older amronet wrote without a manifest — makes the command refuse with one line that names
it, before anything is written. The current folder and the folders that contain it are refused too: they cannot
be replaced.

The new content is written into a hidden staging folder beside the output folder (``.amronet-tmp-`` and random
characters, whatever the output's name) and renamed into place at the end, so an interrupted or failed command
leaves either the previous output or the complete new one, never half-written files.

Single files (``snapshot --out pic.png``) are written to a temporary sibling and renamed over the path the user
named, as ``cp`` or ``-o`` would.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from amronet.errors import AmronetError

__all__ = ["MANIFEST", "check_output_folder", "write_file_atomically", "write_files_atomically"]

MANIFEST = ".amronet-manifest.json"
"""The file in every folder amronet writes that lists the files it wrote there, with their SHA-256."""

_SQLITE_SIDE_FILES = ("-wal", "-shm", "-journal")

_STAGING = ".amronet-tmp-"
"""Prefix of the staging folders and files (``mkdtemp`` adds 8 random characters): a short name of its own, not
the output's, so that an output named with the longest name the file system takes (255 bytes) can be staged too;
the output's own name is given only by the final rename."""

_RETIRED = ".amronet-old-"
"""Prefix of the folder the previous output is moved into, just before it is deleted."""


def check_output_folder(out_dir: str | Path, keep: Iterable[str] = (), option: str = "--out") -> Path:
    """Check that amronet may write ``out_dir`` as a whole, before any work is done.

    Args:
        out_dir: The folder the command will write.
        keep: Names of files in the folder that the command keeps (a result store and its SQLite side files).
        option: The option that named the folder, for the error message.

    Returns:
        ``out_dir`` as a path.

    Raises:
        AmronetError: The path is empty, is the current folder or contains it, is a symbolic link, exists and is
            not a folder, or holds anything amronet did not write there (named in the message).
    """
    if not str(out_dir).strip():
        raise AmronetError(f"{option}: empty path; name a folder, e.g. runs/a")
    out_dir = Path(out_dir)
    where = str(out_dir)
    resolved = out_dir.resolve()
    if resolved == Path.cwd().resolve() or resolved in Path.cwd().resolve().parents:
        raise AmronetError(f"{option}: {where!r} is the current folder or contains it and cannot be replaced; "
                           "name a new folder, e.g. runs/a")
    if not os.path.lexists(out_dir):
        return out_dir
    if out_dir.is_symlink():
        raise AmronetError(f"{option}: {where!r} is a symbolic link; amronet writes only into a real folder, not "
                           "through a link: give the folder itself or another path")
    if not out_dir.is_dir():
        raise AmronetError(f"{option}: {where!r} exists and is not a folder; choose another path")
    foreign = _foreign_entries(out_dir, _kept_names(keep))
    if foreign:
        shown = ", ".join(repr(name) for name in foreign[:3])
        more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
        them = "it" if len(foreign) == 1 else "them"
        raise AmronetError(f"{option}: {where!r} holds {shown}{more}, which amronet did not write there (or changed "
                           f"since); move {them} away or choose a new or empty folder; nothing was changed")
    return out_dir


def write_files_atomically(out_dir: str | Path, files: Mapping[str, bytes], keep: Iterable[str] = (),
                           option: str = "--out") -> Path:
    """Write ``files`` as the complete content of ``out_dir``, all at once, with a manifest.

    ``out_dir`` must pass :func:`check_output_folder`. An existing one is replaced only after the new content is
    complete on disk. Files of the old folder named in ``keep`` (e.g. a result store) are carried over by hard
    link (or copy), so they exist at every moment.

    Raises:
        AmronetError: ``out_dir`` may not be written (see :func:`check_output_folder`), or cannot be written.
    """
    keep = tuple(keep)
    out_dir = check_output_folder(out_dir, keep, option)
    if MANIFEST in files:
        raise ValueError(f"{MANIFEST} is amronet's own file; do not pass it")
    parent = out_dir.parent if str(out_dir.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=_STAGING, dir=parent))
    except OSError as exc:
        raise AmronetError(f"{option}: cannot write to {str(parent)!r}: {exc.strerror}") from None
    try:
        os.chmod(staging, _permissions(0o777))  # mkdtemp makes it private; results are as shareable as any file
        manifest = {"written_by": "amronet", "files": {}}
        for name, content in files.items():
            _write_synced(staging / name, content)
            manifest["files"][name] = hashlib.sha256(content).hexdigest()
        for name in _kept_names(keep):
            if name not in files and (out_dir / name).is_file():
                try:
                    os.link(out_dir / name, staging / name)
                except OSError:
                    shutil.copy2(out_dir / name, staging / name)
        _write_synced(staging / MANIFEST, (json.dumps(manifest, indent=1, sort_keys=True) + "\n").encode())
        old = None
        if out_dir.exists():
            old = Path(tempfile.mkdtemp(prefix=_RETIRED, dir=parent))
            os.replace(out_dir, old / "previous")
        os.replace(staging, out_dir)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return out_dir


def write_file_atomically(path: str | Path, write: Callable[[Path], object], option: str = "--out") -> Path:
    """Create ``path`` by calling ``write(tmp_path)`` on a temporary sibling and renaming it into place."""
    path = Path(path)
    if path.is_dir():
        raise AmronetError(f"{option}: {str(path)!r} is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=_STAGING, suffix=path.suffix, dir=path.parent)
        os.close(fd)
    except OSError as exc:
        raise AmronetError(f"{option}: cannot write {str(path)!r}: {exc.strerror}") from None
    try:
        write(Path(tmp))
        os.chmod(tmp, _permissions(0o666))  # mkstemp makes it private
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _kept_names(keep: Iterable[str]) -> set[str]:
    """The kept files and, for SQLite stores, their side files."""
    names = set()
    for name in keep:
        names.add(name)
        names.update(name + side for side in _SQLITE_SIDE_FILES)
    return names


def _foreign_entries(out_dir: Path, kept: set[str]) -> list[str]:
    """Entries of ``out_dir`` that amronet may not replace: not in its manifest (or changed since), not kept."""
    written = _manifest_files(out_dir)
    foreign = []
    for entry in sorted(os.scandir(out_dir), key=lambda e: e.name):
        name = entry.name
        if name in kept and entry.is_file(follow_symlinks=False):
            continue
        if name == MANIFEST and written is not None:
            continue
        mode = entry.stat(follow_symlinks=False).st_mode
        if written is None or name not in written or not stat.S_ISREG(mode):
            foreign.append(name + ("/" if stat.S_ISDIR(mode) else ""))
        elif _sha256(Path(entry.path)) != written[name]:
            foreign.append(name)
    return foreign


def _manifest_files(out_dir: Path) -> dict[str, str] | None:
    """The files the manifest of ``out_dir`` lists (name → SHA-256), or None without a readable manifest."""
    path = out_dir / MANIFEST
    if path.is_symlink() or not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        files = data["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not isinstance(files, dict) or not all(isinstance(v, str) for v in files.values()):
        return None
    return files


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(functools.partial(fh.read, 1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _write_synced(path: Path, content: bytes) -> None:
    with open(path, "wb") as fh:
        fh.write(content)
        fh.flush()
        os.fsync(fh.fileno())


@functools.cache
def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _permissions(mode: int) -> int:
    """``mode`` as the user's umask leaves it: what a plain ``open()`` or ``mkdir()`` would have given."""
    return mode & ~_umask()
