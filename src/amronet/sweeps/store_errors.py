"""The result store's errors: every SQLite error of a store's connection becomes one :class:`StoreError` line.

A store's connection is a :class:`GuardedConnection`: its statements and their cursors (``fetchone``,
``fetchall``, iterating) turn an SQLite error — a damaged page (``database disk image is malformed``), text that is
not UTF-8, a read-only file, a full disk, a lock held too long — into a :class:`StoreError` that names the file,
says what is wrong and how to go on. Stored JSON that does not parse is a damaged store too (:func:`stored_json`).
Nothing is written to a damaged store: its transaction rolls back, and the file is left as it was.

Errors in the use of the API (``sqlite3.ProgrammingError``, ``sqlite3.InterfaceError``) are bugs, not damage: they
pass unchanged.
"""

from __future__ import annotations

import json
import shlex
import sqlite3
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError

__all__ = ["GuardedConnection", "GuardedCursor", "StoreError", "store_error", "stored_json"]


class StoreError(AmronetError):
    """The result store cannot be used (not a store, damaged, unreadable, read-only, a newer schema)."""


_DAMAGED = ("malformed", "not a database", "could not decode", "corrupt")


def _recover_hint(path: Path) -> str:
    return (f"recover what it holds with `sqlite3 {shlex.quote(str(path))} .recover | sqlite3 recovered.sqlite`, "
            "or give a new file name")


def store_error(exc: sqlite3.Error, path: Path, option: str) -> StoreError:
    """The one-line :class:`StoreError` for an SQLite error ``exc`` of the store at ``path``.

    Args:
        exc: What SQLite raised.
        path: The store's file.
        option: How the message names the path (``--store`` or ``STORE``).
    """
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    low = text.lower()
    shown = repr(str(path))
    if any(word in low for word in _DAMAGED):
        if "could not decode" in low:  # SQLite quotes the undecodable text: name the column only
            text = text.split(" with text ")[0]
        return StoreError(f"{option}: {shown} is damaged ({text}); it was left as it was: {_recover_hint(path)}")
    if "readonly" in low or "read-only" in low:
        return StoreError(f"{option}: {shown} is read-only ({text}; SQLite writes beside a store even to read "
                          "it); make it and its folder writable, or copy it to a folder that is")
    if "locked" in low or "busy" in low:
        return StoreError(f"{option}: {shown} stayed locked by another process ({text}); try again when it is done")
    if "full" in low:
        return StoreError(f"{option}: the disk holding {shown} is full ({text}); free some space and run again")
    return StoreError(f"{option}: cannot use the result store {shown} ({text})")


def stored_json(text: str, path: Path, option: str, what: str) -> Any:
    """Decode JSON text read from the store (``what``: which column); damaged text is a :class:`StoreError`."""
    try:
        return json.loads(text)
    except (ValueError, TypeError) as exc:
        raise StoreError(f"{option}: {str(path)!r} is damaged ({what} is not JSON: {exc}); it was left as it was: "
                         f"{_recover_hint(path)}") from None


class _Guard:
    """Turns the SQLite errors of one store into :class:`StoreError`."""

    def __init__(self, path: Path, option: str) -> None:
        self.path = path
        self.option = option

    @contextmanager
    def __call__(self) -> Iterator[None]:
        try:
            yield
        except (sqlite3.ProgrammingError, sqlite3.InterfaceError):
            raise
        except sqlite3.Error as exc:
            raise store_error(exc, self.path, self.option) from None


class GuardedCursor:
    """A cursor whose reads raise :class:`StoreError` instead of SQLite's errors."""

    def __init__(self, cursor: sqlite3.Cursor, guard: _Guard) -> None:
        self._cursor = cursor
        self._guard = guard

    @property
    def description(self) -> Any:
        """The columns of the result (as :attr:`sqlite3.Cursor.description`)."""
        return self._cursor.description

    def fetchone(self) -> Any:
        """The next row, or ``None``."""
        with self._guard():
            return self._cursor.fetchone()

    def fetchall(self) -> list[Any]:
        """The remaining rows."""
        with self._guard():
            return self._cursor.fetchall()

    def __iter__(self) -> Iterator[Any]:
        with self._guard():  # once around the whole walk: rows come at SQLite's pace
            yield from self._cursor


class GuardedConnection:
    """A store's SQLite connection whose statements raise :class:`StoreError` instead of SQLite's errors.

    Args:
        conn: The open connection.
        path: The store's file, as the messages name it.
        option: How the messages name the path (``--store`` or ``STORE``).

    Attributes:
        raw: The connection itself (for code that handles SQLite's errors, e.g. retrying a busy database).
    """

    def __init__(self, conn: sqlite3.Connection, path: Path, option: str) -> None:
        self.raw = conn
        self.guard = _Guard(path, option)

    def execute(self, sql: str, parameters: Any = ()) -> GuardedCursor:
        """Run one statement (as :meth:`sqlite3.Connection.execute`)."""
        with self.guard():
            return GuardedCursor(self.raw.execute(sql, parameters), self.guard)

    def executemany(self, sql: str, rows: Iterable[Iterable[Any]]) -> GuardedCursor:
        """Run one statement for each of ``rows``."""
        with self.guard():
            return GuardedCursor(self.raw.executemany(sql, rows), self.guard)

    def executescript(self, script: str) -> None:
        """Run several statements."""
        with self.guard():
            self.raw.executescript(script)

    @property
    def in_transaction(self) -> bool:
        """Whether a transaction is open."""
        return self.raw.in_transaction

    def close(self) -> None:
        """Close the connection (an error closing a damaged store is one :class:`StoreError` too)."""
        with self.guard():
            self.raw.close()
