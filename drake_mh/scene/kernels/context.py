"""A scene's unpacked arrays and a check's workspaces behind one pointer, for compiled callers.

The batched state check (:func:`drake_mh.scene.kernels.states.check_states`) reads 28 arrays of
the scene and 25 of its workspace. Passed as two tuples, a call copies every array's fields
(pointer, shape, strides: about 450 machine words) and costs about 0.3 µs more than the same
call on a few arrays (measured on forward kinematics alone, 1 state: 0.58 against 0.27 µs), on
calls that cost 1.2-2 µs for 1-8 states. A :class:`CheckContext` (a numba ``StructRef``) is
passed as one pointer; its fields are read where they are used.

Typical use (compiled code)::

    ctx = CheckContext(arrays, ws, mws)   # once per plan
    check_states(QT, n0, m, ..., ctx, out, tau)
"""

from __future__ import annotations

from numba.core import types
from numba.experimental import structref


@structref.register
class CheckContextType(types.StructRef):
    """numba type of :class:`CheckContext` (one per combination of field types)."""

    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class CheckContext(structref.StructRefProxy):
    """``(arrays, ws, mws)``: the scene's unpacked arrays (:func:`drake_mh.scene.kernels.packing.unpack`),
    the state check's workspace (:func:`drake_mh.scene.kernels.states.state_workspace`) and the
    caller's own workspace (``rrt_connect``: :func:`drake_mh.planning.motion.check.motion_workspace`;
    anything, e.g. ``None``, for a caller that has none). Holds references to them, unless they
    are borrowed (:mod:`drake_mh._support.borrow`): then whoever owns them must keep them alive."""


structref.define_proxy(CheckContext, CheckContextType, ["arrays", "ws", "mws"])
