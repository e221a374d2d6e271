"""The running union of the cells heard from a set of nodes, with the node that marked each cell first.

:class:`~amronet.engine.coverage_heard.HeardCells` keeps one or two :class:`HeardUnion` per coverage area. A node
that joins marks only the cells nobody covers yet. A node that leaves costs only the cells it marked first, and
those are decided again only by the members that joined after it (and whose reach touches them): when it joined,
every cell it marked was uncovered, so no older member hears it. A cell's decision depends on the node and the
cell alone (:func:`amronet.engine.hearing.heard_cells`), so the union is the one a fresh pass over the members
marks, bit for bit.

Its invariant: a cell is in the union exactly when a member hears it, and no member that joined before the cell's
owner hears it. Joining keeps it (the new member is the youngest and marks only uncovered cells); leaving keeps it
because the freed cells are decided again by the younger members in the order they joined.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from amronet.engine.cell_boxes import BLOCK

__all__ = ["BYTES_PER_CELL", "HeardUnion", "Mark", "block_grid", "full_window"]

BYTES_PER_CELL = 6
"""What a union keeps per cell: the union (1 byte), the owner (4), the cells to decide again (1)."""

Mark = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int, int], np.ndarray],
                int]
"""``mark(xy, keys, mask, covered, owner, window, blocks)``: :func:`~amronet.engine.hearing.heard_cells` of one
grid."""


def full_window(shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """The window ``(i0, i1, j0, j1)`` of every cell of a grid of ``shape``."""
    return 0, shape[0] - 1, 0, shape[1] - 1


def block_grid(shape: tuple[int, int]) -> np.ndarray:
    """One 1 per block of a grid of ``shape`` (every block may hold a cell to decide; see ``heard_cells``)."""
    return np.ones((-(-shape[0] // BLOCK), -(-shape[1] // BLOCK)), dtype=np.uint8)


class HeardUnion:
    """The cells of one coverage area heard from a set of member nodes, kept as members join and leave.

    Args:
        shape: The area's grid shape.
        boxes: ``boxes(xy)``: for each position of ``xy`` ``(N, 2)``, rows ``(i0, i1, j0, j1)`` ``(N, 4)`` that
            hold every cell its node can mark.

    Attributes:
        union: The cells heard from some member.
        owner: Per cell, the slot of the member that marked it (-1: none).
        members: A member's position -> its slot.
        dropped: The positions that left at the last update (met again, two callers alternate: see
            :class:`~amronet.engine.coverage_heard.HeardCells`).
        used: When it last served a call (its keeper's clock).
        blocks: Per block of cells, 0 when it holds no cell of the area's mask outside the union (the kernel
            skips it; a member that leaves opens the blocks of its cells again).
    """

    def __init__(self, shape: tuple[int, int], boxes: Callable[[np.ndarray], np.ndarray]) -> None:
        self.union = np.zeros(shape, dtype=bool)
        self.blocks = block_grid(shape)
        self.owner = np.full(shape, -1, dtype=np.int32)
        self._todo = np.zeros(shape, dtype=bool)
        self._todo_read = self._todo.view()  # what the kernel reads: read-only like an area's mask (one compile)
        self._todo_read.flags.writeable = False
        self._boxes_of = boxes
        self.members: dict[tuple[float, float], int] = {}
        self.dropped: set[tuple[float, float]] = set()
        self.used = 0
        self._xy = np.zeros((0, 2))
        self._box = np.zeros((0, 4), dtype=np.intp)
        self._joined = np.zeros(0, dtype=np.int64)
        self._count = 0
        self._free: list[int] = []

    @property
    def nbytes(self) -> int:
        """Bytes its grids take."""
        return self.union.size * BYTES_PER_CELL

    def clear(self) -> None:
        """No member left (the grids kept)."""
        self.union[:] = False
        self.blocks[:] = 1
        self.owner[:] = -1
        self.members.clear()
        self.dropped = set()
        self._free = list(range(len(self._xy) - 1, -1, -1))

    def become(self, other: HeardUnion) -> None:
        """Take ``other``'s members and grids (copies; its keeper's clock and last leavers are not taken)."""
        np.copyto(self.union, other.union)
        np.copyto(self.blocks, other.blocks)
        np.copyto(self.owner, other.owner)
        self.members = dict(other.members)
        self.dropped = set()
        self._xy, self._box, self._joined = other._xy.copy(), other._box.copy(), other._joined.copy()
        self._count = other._count
        self._free = list(other._free)

    def changes(self, positions: dict[tuple[float, float], None]
                ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
        """The members not among ``positions`` (to leave) and the ``positions`` not members (to join)."""
        gone = [key for key in self.members if key not in positions]
        new = [key for key in positions if key not in self.members]
        return gone, new

    def update(self, gone: list[tuple[float, float]], new: list[tuple[float, float]], mask: np.ndarray,
               mark: Mark) -> None:
        """Members ``gone`` leave and the positions ``new`` join; ``mask``: the area's cells.

        The cells a leaving member marked first are decided again by the younger members that remain, then the
        new ones mark the cells still uncovered, in the order given.
        """
        if gone:
            self._leave([self.members.pop(key) for key in gone], mark)
        self.dropped = set(gone)
        if new:
            slots = self._slots(len(new))
            xy = np.array(new, dtype=float).reshape(-1, 2)
            self._xy[slots] = xy
            self._box[slots] = self._boxes_of(xy)
            self._joined[slots] = np.arange(self._count, self._count + len(new))
            self._count += len(new)
            for key, slot in zip(new, slots.tolist(), strict=True):
                self.members[key] = slot
            mark(xy, slots, mask, self.union, self.owner, full_window(mask.shape), self.blocks)

    def _leave(self, slots: list[int], mark: Mark) -> None:
        """Unmark the cells the members in ``slots`` own and decide them again by the younger members left."""
        oldest = self._joined[slots].min()
        box = self._box[slots]
        i0, i1, j0, j1 = int(box[:, 0].min()), int(box[:, 1].max()), int(box[:, 2].min()), int(box[:, 3].max())
        leaving = np.zeros(len(self._xy) + 1, dtype=bool)  # by slot + 1: a cell without owner (-1) is not theirs
        leaving[np.asarray(slots) + 1] = True
        owner = self.owner[i0:i1 + 1, j0:j1 + 1]  # every cell they marked: each marked in its own box only
        mine = leaving[owner + 1]
        self._free.extend(slots)
        rows, cols = np.flatnonzero(mine.any(axis=1)), np.flatnonzero(mine.any(axis=0))
        if len(rows) == 0:  # they marked no cell first
            return
        self.union[i0:i1 + 1, j0:j1 + 1][mine] = False
        freed = _blocks_holding(mine, i0, j0)  # the blocks of their cells: to decide again
        self.blocks[i0 // BLOCK:i1 // BLOCK + 1, j0 // BLOCK:j1 // BLOCK + 1] |= freed
        todo_blocks = np.zeros_like(self.blocks)  # the pass looks at those blocks only
        todo_blocks[i0 // BLOCK:i1 // BLOCK + 1, j0 // BLOCK:j1 // BLOCK + 1] = freed
        self._todo[i0:i1 + 1, j0:j1 + 1][mine] = True
        owner[mine] = -1
        window = (i0 + int(rows[0]), i0 + int(rows[-1]), j0 + int(cols[0]), j0 + int(cols[-1]))
        rest = np.fromiter(self.members.values(), dtype=np.int32, count=len(self.members))
        box = self._box[rest]
        near = rest[(box[:, 0] <= window[1]) & (box[:, 1] >= window[0]) & (box[:, 2] <= window[3])
                    & (box[:, 3] >= window[2]) & (self._joined[rest] > oldest)]
        near = near[np.argsort(self._joined[near], kind="stable")]  # oldest first: the invariant (module doc)
        if len(near):
            # (the pass sees the cells to decide again only: what it finds of the blocks is not kept)
            mark(self._xy[near], near, self._todo_read, self.union, self.owner, window, todo_blocks)
        self._todo[window[0]:window[1] + 1, window[2]:window[3] + 1] = False

    def _slots(self, n: int) -> np.ndarray:
        """``n`` free slots, the arrays grown when too few are free."""
        short = n - len(self._free)
        if short > 0:
            size = len(self._xy)
            grow = max(short, size)
            self._xy = np.concatenate([self._xy, np.zeros((grow, 2))])
            self._box = np.concatenate([self._box, np.zeros((grow, 4), dtype=np.intp)])
            self._joined = np.concatenate([self._joined, np.zeros(grow, dtype=np.int64)])
            self._free.extend(range(size + grow - 1, size - 1, -1))
        return np.array([self._free.pop() for _ in range(n)], dtype=np.int32)


def _blocks_holding(cells: np.ndarray, i0: int, j0: int) -> np.ndarray:
    """Which blocks hold a true cell of ``cells``, a window of a grid that starts at cell ``(i0, j0)``.

    Returns:
        Per block of :data:`BLOCK` cells a side that the window touches, from ``(i0 // BLOCK, j0 // BLOCK)``: 1
        where it holds a true cell, else 0 (``uint8``). A block's row of 8 cells is one 8-byte word.
    """
    rows, cols = cells.shape
    di, dj = i0 % BLOCK, j0 % BLOCK
    nb_r, nb_c = -(-(di + rows) // BLOCK), -(-(dj + cols) // BLOCK)
    padded = np.zeros((nb_r * BLOCK, nb_c * BLOCK), dtype=bool)
    padded[di:di + rows, dj:dj + cols] = cells
    words = padded.view(np.uint64).reshape(nb_r, BLOCK, nb_c)  # a block's row of 8 cells: one word
    return (np.bitwise_or.reduce(words, axis=1) != 0).view(np.uint8)
