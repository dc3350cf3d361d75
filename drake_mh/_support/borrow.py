"""Borrowed arrays: views that compiled callees pass around without reference counting.

Numba counts references to every array an ``njit`` function receives: a function's entry
increments the count of each array argument it keeps (an atomic add each, through a call to
``NRT_incref``) and its exits decrement them, where LLVM's pruning of those pairs gives up
(large functions with many exits, as the planner's kernels are). The motion check of
``rrt_connect`` passes the scene's 28 arrays and a workspace of 22 down three calls per motion:
about 100 atomic operations per call, 0.65 µs measured for a call of ``_motion`` that returned
at once, a fifth of a MotionBenchMaker plan's time.

:func:`borrow` returns the same array (same type, data, shape and strides) without its
``meminfo``: numba's increments and decrements skip a null ``meminfo``, so passing a borrowed
array costs a null test. A tuple (nested or not) of arrays is borrowed element by element. The
price is ownership: a borrowed array (and every view of it) must not outlive the array it was
borrowed from; borrow inside a call that holds the owner (e.g. borrow the call's own
arguments), and never return or store what was borrowed.
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array

__all__ = ["borrow"]


def _borrowable(typ) -> bool:
    if isinstance(typ, types.Array):
        return True
    return isinstance(typ, types.BaseTuple) and all(_borrowable(t) for t in typ.types)


def _borrowed(context, builder, typ, value):
    """LLVM value of ``value`` (of numba type ``typ``) with every array's meminfo and parent null."""
    if isinstance(typ, types.Array):
        result = make_array(typ)(context, builder, value=value)
        result.meminfo = cgutils.get_null_value(result.meminfo.type)
        result.parent = cgutils.get_null_value(result.parent.type)
        return result._getvalue()
    items = [_borrowed(context, builder, t, builder.extract_value(value, i)) for i, t in enumerate(typ.types)]
    return context.make_tuple(builder, typ, items)


@intrinsic
def borrow(typingctx, owned):
    """``owned`` (an array, or a tuple of arrays and such tuples) without reference counting
    (module docstring): the caller must hold the owner for as long as the result, or a view of
    it, is used."""
    if not _borrowable(owned):
        return None

    def codegen(context, builder, signature, args):
        return _borrowed(context, builder, owned, args[0])

    return owned(owned), codegen
