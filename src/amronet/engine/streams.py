"""The random streams of several runs stepped together in one set of arrays (:mod:`amronet.sim.batch`).

A run draws its random numbers from its own ``numpy.random.Generator``, seeded by the run's seed. When several
runs share one set of arrays, every draw a controller makes for some robots is split by run: each run's robots
get numbers from that run's generator, in the order the run would have drawn them on its own, so a run gives the
same result bit for bit whether it is stepped alone or in a batch. Code that draws per step goes through
:func:`draw_per_run`, which takes either a plain generator (one run) or :class:`RunStreams`; the walkers' pair of
draws, the most frequent, has its own shorter path (:func:`normal_then_uniform`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from amronet.engine import bitgen

__all__ = ["RunStreams", "compiled_streams", "draw_per_run", "normal_then_uniform"]

Draw = Callable[[np.random.Generator, int], tuple[np.ndarray, ...]]
"""``draw(generator, m)`` returns arrays of ``m`` numbers each, drawn in a fixed order."""


class RunStreams:
    """One generator per run, for runs whose robots are contiguous blocks of the shared arrays.

    Args:
        generators: The runs' generators, in block order.
        starts: First robot index of every run's block and, last, the total number of robots ``(G + 1,)``.
    """

    def __init__(self, generators: Sequence[np.random.Generator], starts: np.ndarray) -> None:
        self.generators = list(generators)
        self.starts = np.asarray(starts, dtype=np.int64)
        if len(self.starts) != len(self.generators) + 1:
            raise ValueError(f"starts needs {len(self.generators) + 1} entries, got {len(self.starts)}")

    def draw(self, who: np.ndarray, draw: Draw) -> tuple[np.ndarray, ...]:
        """Numbers for the robots ``who``: each run's robots draw from its generator, in their order in ``who``.

        Returns:
            The arrays ``draw`` returns, each of ``len(who)`` entries aligned with ``who``.
        """
        who = np.asarray(who, dtype=np.int64)
        run = np.searchsorted(self.starts, who, side="right") - 1
        counts = np.bincount(run, minlength=len(self.generators))
        drawn = [draw(self.generators[g], int(counts[g])) for g in np.flatnonzero(counts)]
        if not drawn:  # nobody draws: the shapes and types of a zero-size draw
            return tuple(p[:0] for p in draw(np.random.default_rng(0), 0))
        joined = tuple(np.concatenate(parts) for parts in zip(*drawn, strict=True))
        if len(run) > 1 and np.any(run[1:] < run[:-1]):  # not grouped by run already: put every number in place
            order = np.argsort(run, kind="stable")
            out = tuple(np.empty_like(j) for j in joined)
            for o, j in zip(out, joined, strict=True):
                o[order] = j
            return out
        return joined

    def normal_then_uniform(self, who: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`draw` of ``m`` standard normal, then ``m`` standard uniform numbers per run, written in place.

        The same numbers as ``draw(who, lambda g, m: (g.standard_normal(m), g.random(m)))``: each run's generator
        fills its robots' slices of the two arrays directly, without the joins (a batch draws this every step).
        """
        who = np.asarray(who, dtype=np.int64)
        if len(who) > 1 and np.any(who[1:] < who[:-1]):  # not in order: the general path puts them in place
            return self.draw(who, _normal_uniform)  # type: ignore[return-value]
        normal, uniform = np.empty(len(who)), np.empty(len(who))
        bounds = np.searchsorted(who, self.starts).tolist()  # who[bounds[g]:bounds[g + 1]]: run g's robots
        for gen, a, b in zip(self.generators, bounds[:-1], bounds[1:], strict=True):
            if b > a:
                gen.standard_normal(out=normal[a:b])
                gen.random(out=uniform[a:b])
        return normal, uniform


def _normal_uniform(rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray]:
    return rng.standard_normal(m), rng.random(m)


def normal_then_uniform(rng: np.random.Generator | RunStreams, who: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the robots ``who``: ``m`` standard normal, then ``m`` standard uniform numbers from each one's run.

    What a walker draws every step (heading noise, then a fresh heading where it needs one); the calls are
    ``standard_normal`` and ``random`` because they cost less than ``normal`` and ``uniform`` and give the same
    numbers once scaled. The result equals :func:`draw_per_run` with that pair of draws, bit for bit.
    """
    if isinstance(rng, RunStreams):
        return rng.normal_then_uniform(who)
    return _normal_uniform(rng, len(who))


def draw_per_run(rng: np.random.Generator | RunStreams, who: np.ndarray, draw: Draw) -> tuple[np.ndarray, ...]:
    """Draw numbers for the robots ``who`` from one run's generator or, batched, from each robot's run's.

    Args:
        rng: The run's generator, or the :class:`RunStreams` of a batch.
        who: The robots that draw, ``(M,)``.
        draw: ``draw(generator, m)``: the numbers of ``m`` robots, as a tuple of arrays of ``m`` entries.
    """
    if isinstance(rng, RunStreams):
        return rng.draw(who, draw)
    return draw(rng, len(who))


def compiled_streams(rng: np.random.Generator | RunStreams, n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """``(bitgens, starts)`` of :func:`amronet.engine.bitgen.draw_normal_uniform` for ``n`` robots drawing from ``rng``.

    One run's generator owns all ``n`` robots; a batch's streams, each run its block. The generators must outlive the
    arrays' use (the controller holding ``rng`` keeps them). ``None`` when the compiled draws are not available
    (:data:`amronet.engine.bitgen.AVAILABLE`): the caller draws through numpy.
    """
    if not bitgen.AVAILABLE:
        return None
    if isinstance(rng, RunStreams):
        return bitgen.addresses(rng.generators), rng.starts.copy()
    return bitgen.addresses([rng]), np.array([0, n], dtype=np.int64)
