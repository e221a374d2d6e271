"""Draws from numpy's generators inside compiled code: the same numbers as ``Generator.standard_normal`` and ``random``.

A compiled kernel cannot take a ``numpy.random.Generator`` cheaply (numba unboxes one in about 12 µs per call), but
every numpy bit generator exposes its C interface: the address of a ``bitgen_t`` struct (``{void *state;
uint64_t (*next_uint64)(void *); uint32_t (*next_uint32)(void *); double (*next_double)(void *); ...}``, numpy's
``BitGenerator.ctypes.bit_generator``). Kernels here are given those addresses as plain integers and call the bit
generator's own functions through them, so the generator's state advances in place, exactly as numpy's methods
advance it. On top, :func:`standard_normal` is numpy's ziggurat (``random_standard_normal`` in numpy's
``distributions.c``, as numba's own port and tables have it) and :func:`next_double` is numpy's ``random()``; the
tests draw both ways and compare bit for bit.

The generator must stay alive while its address is in use (the caller keeps it), and no other thread may draw from
it meanwhile (numpy's methods take the generator's lock; these calls do not).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

try:  # numba's copy of numpy's ziggurat tables (a private module of numba: checked bit for bit by the tests)
    from numba.np.random._constants import fi_double, ki_double, wi_double, ziggurat_nor_inv_r, ziggurat_nor_r
except ImportError:  # pragma: no cover - a numba without them: the walkers draw through numpy, as before
    AVAILABLE = False
else:
    AVAILABLE = True

__all__ = ["AVAILABLE", "addresses", "draw_normal_uniform", "next_double", "standard_normal"]

_I8P = ir.IntType(8).as_pointer()
_BITGEN = ir.LiteralStructType([
    _I8P,
    ir.FunctionType(ir.IntType(64), [_I8P]).as_pointer(),
    ir.FunctionType(ir.IntType(32), [_I8P]).as_pointer(),
    ir.FunctionType(ir.DoubleType(), [_I8P]).as_pointer(),
    ir.FunctionType(ir.IntType(64), [_I8P]).as_pointer(),
])
"""numpy's ``bitgen_t``: the state, then ``next_uint64``, ``next_uint32``, ``next_double``, ``next_raw``."""


def _call(builder: ir.IRBuilder, address: ir.Value, field: int) -> ir.Value:
    """Call the bitgen_t function in ``field`` of the struct at ``address`` with the struct's state."""
    struct = builder.inttoptr(address, _BITGEN.as_pointer())
    zero = ir.Constant(ir.IntType(32), 0)
    state = builder.load(builder.gep(struct, [zero, zero]))
    fn = builder.load(builder.gep(struct, [zero, ir.Constant(ir.IntType(32), field)]))
    return builder.call(fn, [state])


@intrinsic
def next_uint64(typingctx, address):  # pragma: no cover - numba
    """The next 64 random bits of the bit generator whose ``bitgen_t`` is at ``address`` (its ``next_uint64``)."""
    if address != types.int64:
        return None
    return types.uint64(types.int64), lambda context, builder, signature, args: _call(builder, args[0], 1)


@intrinsic
def next_double(typingctx, address):  # pragma: no cover - numba
    """The next double in [0, 1) of the bit generator at ``address``: what ``Generator.random`` draws."""
    if address != types.int64:
        return None
    return types.float64(types.int64), lambda context, builder, signature, args: _call(builder, args[0], 3)


def addresses(generators: Sequence[np.random.Generator]) -> np.ndarray:
    """The ``bitgen_t`` addresses of the generators' bit generators, int64 ``(G,)``, for the kernels here."""
    return np.array([g.bit_generator.ctypes.bit_generator.value for g in generators], dtype=np.int64)


@njit(cache=True)
def standard_normal(address):  # pragma: no cover - numba
    """A standard normal number from the bit generator at ``address``: what ``Generator.standard_normal`` draws."""
    while 1:
        r = next_uint64(address)
        idx = r & 0xff
        r >>= 8
        sign = r & 0x1
        rabs = (r >> 1) & 0x000fffffffffffff
        x = rabs * wi_double[idx]
        if sign & 0x1:
            x = -x
        if rabs < ki_double[idx]:
            return x
        if idx == 0:
            while 1:
                xx = -ziggurat_nor_inv_r * np.log1p(-next_double(address))
                yy = -np.log1p(-next_double(address))
                if yy + yy > xx * xx:
                    if (rabs >> 8) & 0x1:
                        return -(ziggurat_nor_r + xx)
                    return ziggurat_nor_r + xx
        elif (fi_double[idx - 1] - fi_double[idx]) * next_double(address) + fi_double[idx] < np.exp(-0.5 * x * x):
            return x


@njit(cache=True)
def draw_normal_uniform(bitgens, starts, who, normal, uniform):  # pragma: no cover - numba
    """For the robots ``who`` (ascending): per run, ``m`` standard normals, then ``m`` uniforms from its generator.

    Run ``g`` owns robots ``starts[g] .. starts[g + 1] - 1`` and draws from the bit generator at ``bitgens[g]``; its
    ``m`` robots in ``who`` get their numbers in ``normal`` and ``uniform`` at their places in ``who``. The same numbers
    as :meth:`amronet.engine.streams.RunStreams.normal_then_uniform`. ``False`` (nothing drawn) if ``who`` is not
    ascending or names a robot outside the runs.
    """
    n = who.shape[0]
    for k in range(n):
        if who[k] < starts[0] or who[k] >= starts[starts.shape[0] - 1] or (k > 0 and who[k] <= who[k - 1]):
            return False
    g = 0
    a = 0
    while a < n:
        while who[a] >= starts[g + 1]:
            g += 1
        b = a
        while b < n and who[b] < starts[g + 1]:
            b += 1
        address = bitgens[g]
        for k in range(a, b):
            normal[k] = standard_normal(address)
        for k in range(a, b):
            uniform[k] = next_double(address)
        a = b
    return True
