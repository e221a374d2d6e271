"""Signals: holding Ctrl-C back while processes are started, so that a worker never sees it before it ignores it."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator

__all__ = ["sigint_deferred"]


@contextlib.contextmanager
def sigint_deferred() -> Iterator[None]:
    """Block ``SIGINT`` in this thread within the block (processes forked meanwhile start with it blocked).

    A Ctrl-C meanwhile is delivered as the block ends (``KeyboardInterrupt`` there).
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)
