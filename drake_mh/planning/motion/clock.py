"""A monotonic clock inside compiled code, so that a planner honours its deadline without
returning to Python: libc's ``clock_gettime`` called through its address.

The address is a plain integer argument of the kernel (numba's disk cache stays valid across
processes, where the address differs; a ctypes function object as argument works too but
costs 3 µs of dispatch per call). Reading the clock costs about 30 ns (vDSO).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import time

import numba
import numpy as np
from llvmlite import ir
from numba.extending import intrinsic

CLOCK_ID = getattr(time, "CLOCK_MONOTONIC", 1)
"""The clock read; only differences are used (Python passes the seconds left)."""


def clock_address() -> int:
    """Address of libc's ``clock_gettime(clockid_t, struct timespec *)``."""
    libc = ctypes.CDLL(ctypes.util.find_library("c") or None)
    return int(ctypes.cast(libc.clock_gettime, ctypes.c_void_p).value)


@intrinsic
def _clock_gettime(typingctx, address, clock_id, timespec):
    """``((int (*)(int, void *)) address)(clock_id, (void *) timespec)``."""
    sig = numba.types.int32(address, clock_id, timespec)

    def codegen(context, builder, signature, args):
        function_type = ir.FunctionType(ir.IntType(32), [ir.IntType(32), ir.IntType(8).as_pointer()])
        function = builder.inttoptr(args[0], function_type.as_pointer())
        pointer = builder.inttoptr(args[2], ir.IntType(8).as_pointer())
        return builder.call(function, [builder.trunc(args[1], ir.IntType(32)), pointer])

    return sig, codegen


@numba.njit(cache=True, inline="always")
def now(address, timespec):
    """Seconds of the monotonic clock; ``timespec`` a ``(2,)`` int64 scratch array (time_t and
    long on 64-bit Linux and macOS)."""
    _clock_gettime(address, np.int64(CLOCK_ID), timespec.ctypes.data)
    return timespec[0] + 1e-9 * timespec[1]
