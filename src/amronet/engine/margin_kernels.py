"""The compiled kernels that apply a radio model's margin kernel: the link table, coverage and the signal map.

A model gives one margin kernel (and, optionally, a bound of it: :mod:`amronet.engine.hearing`). The kernels that
apply it are written once, calling the path-loss law's (``model_margin`` and ``model_bound`` in
:mod:`amronet.engine.hearing` and :mod:`amronet.engine.links`); for another model :func:`margin_kernels` compiles
copies of them whose ``model_margin`` and ``model_bound`` are the model's (the same code, other globals), so the
model's margin is inlined into every loop just like the built-in law (the copies' ``model_is_path_loss`` is false:
the shortcuts of the built-in law's own pieces are not taken). numba caches the copies on disk like any
kernel: each copy is named after the model's kernels and a digest of the files that define them, so editing a
model's margin compiles its copies afresh.

Example:
    >>> from amronet.engine.hearing import path_loss_bound, path_loss_margin
    >>> margin_kernels(path_loss_margin, path_loss_bound) is PATH_LOSS
    True
"""

from __future__ import annotations

import hashlib
import inspect
import re
import types
from collections.abc import Callable
from typing import Any, NamedTuple

from numba import njit

from amronet.engine import hearing, links
from amronet.engine.hearing import no_bound, path_loss_bound, path_loss_margin

__all__ = ["PATH_LOSS", "MarginKernels", "margin_kernels"]


class MarginKernels(NamedTuple):
    """The compiled kernels of one margin kernel (and bound)."""

    candidate_margins: Any
    """:func:`amronet.engine.links.candidate_margins`: the margin of every candidate link."""
    heard_cells: Any
    """:func:`amronet.engine.hearing.heard_cells`: the cells heard from some node (and, optionally, from which)."""
    best_margin_grid: Any
    """:func:`amronet.engine.hearing.best_margin_grid`: the best margin at every cell."""


PATH_LOSS = MarginKernels(links.path_loss_candidate_margins, hearing.heard_cells, hearing.best_margin_grid)
"""The kernels of the path-loss law (:func:`~amronet.engine.hearing.path_loss_margin` with its bound); its links'
margins by :func:`~amronet.engine.links.path_loss_candidate_margins`, the same numbers as the generic kernel's."""

_COPIES: dict[tuple[Callable, Callable | None], MarginKernels] = {}


def margin_kernels(margin: Callable, bound: Callable | None) -> MarginKernels:
    """The kernels that apply the margin kernel ``margin`` (bounded by ``bound``; ``None``: no bound).

    Args:
        margin: A compiled margin kernel (``@njit``; see :mod:`amronet.engine.hearing`).
        bound: A compiled bound of it, or ``None`` (every cell within reach is tested).

    Returns:
        :data:`PATH_LOSS` for the path-loss law, else copies compiled for ``margin`` (made once per process).
    """
    if margin is path_loss_margin and bound is path_loss_bound:
        return PATH_LOSS
    key = (margin, bound)
    if key not in _COPIES:
        tag = _tag(margin, bound)
        swap = {"model_margin": margin, "model_bound": no_bound if bound is None else bound}
        reach = _copy(hearing.node_reach, swap, tag)
        mark = _copy(hearing._mark_node, {**swap, "model_is_path_loss": False, "node_reach": reach}, tag)
        _COPIES[key] = MarginKernels(_copy(links.candidate_margins, swap, tag),
                                     _copy(hearing.heard_cells, {"_mark_node": mark}, tag),
                                     _copy(hearing.best_margin_grid, swap, tag))
    return _COPIES[key]


def _tag(*kernels: Callable | None) -> str:
    """A name for the copies of ``kernels``: their names and a digest of the source files that define them."""
    digest = hashlib.sha256()
    names = []
    for kernel in kernels:
        if kernel is None:
            continue
        py = getattr(kernel, "py_func", kernel)
        names.append(py.__name__)
        digest.update(py.__module__.encode() + b"\0" + py.__qualname__.encode() + b"\0")
        source = inspect.getsourcefile(py)
        if source is not None:
            with open(source, "rb") as f:
                digest.update(f.read())
    return re.sub(r"\W", "_", "_".join(names)) + "_" + digest.hexdigest()[:12]


def _copy(kernel: Any, swap: dict[str, Any], tag: str) -> Any:
    """``kernel`` compiled again with the globals ``swap`` in place of its module's (cached on disk as ``tag``)."""
    py = kernel.py_func
    env = dict(py.__globals__)
    env.update(swap)
    fn = types.FunctionType(py.__code__, env, py.__name__, py.__defaults__, py.__closure__)
    fn.__qualname__ = f"{py.__qualname__}__{tag}"
    fn.__module__ = py.__module__
    fn.__doc__ = py.__doc__
    options = {k: v for k, v in kernel.targetoptions.items() if k != "nopython"}
    return njit(cache=True, **options)(fn)
