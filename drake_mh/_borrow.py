"""Borrowed arrays: views that compiled callees pass around without reference counting.

Numba counts references to every array an ``njit`` function receives: a function's entry
increments the count of each array argument it keeps (an atomic add each, through a call to
``NRT_incref``) and its exits decrement them, where LLVM's pruning of those pairs gives up
(large functions with many exits, as the planner's kernels are). The motion check of
``rrt_connect`` passes the scene's 28 arrays and a workspace of 17 down three calls per motion:
about 100 atomic operations per call, 0.65 µs measured for a call of ``_motion`` that returned
at once, a fifth of a MotionBenchMaker plan's time.

:func:`borrow` returns the same array (same type, data, shape and strides) without its
``meminfo``: numba's increments and decrements skip a null ``meminfo``, so passing a borrowed
array costs a null test. The price is ownership: a borrowed array (and every view of it) must
not outlive the array it was borrowed from; borrow inside a call that holds the owner, and
never return or store what was borrowed.
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic
from numba.np.arrayobj import make_array

__all__ = ["borrow"]


@intrinsic
def borrow(typingctx, array):
    """``array`` without reference counting (module docstring): the caller must hold the owner
    for as long as the result, or a view of it, is used."""
    if not isinstance(array, types.Array):
        return None

    def codegen(context, builder, signature, args):
        source = make_array(array)(context, builder, value=args[0])
        result = make_array(array)(context, builder, value=source._getvalue())
        result.meminfo = cgutils.get_null_value(result.meminfo.type)
        result.parent = cgutils.get_null_value(result.parent.type)
        return result._getvalue()

    return array(array), codegen
