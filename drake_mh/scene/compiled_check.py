"""The scene's boolean collision check in the compiled core, where it is built.

``drake_mh._native`` (C++ in ``cpp/``, built by ``pip install``: docs/native.md) checks the
sphere model against every obstacle kind and the checked link pairs with the tests of
:func:`drake_mh.scene.kernels.collision.collision_free` and
:func:`drake_mh.scene.kernels.entry.collision_free_one`, in the same order: the same answers,
with nothing compiled at call time. Where the module is not built, or the environment sets
``DRAKE_MH_COMPILED_CORE=0``, those kernels answer (:meth:`drake_mh.scene.batch.CollisionModel.free_function`).
The clearance values and certified segments are bound the same way by
:meth:`drake_mh.scene.batch.CollisionModel.compiled_clearances`.
"""

from __future__ import annotations

from drake_mh._support.native import ENVIRONMENT, compiled_core

__all__ = ["ENVIRONMENT", "compiled_core", "free_function"]


def free_function(model, obstacles: tuple):
    """``f(Q (N, nq), clearance, self_clearance) -> (N,) bool`` (None if ``Q`` is not finite) with
    ``f.make_one() -> (entry, buffer)``: the contract of
    :meth:`drake_mh.scene.batch.CollisionModel.free_function` (``model``'s, against
    ``obstacles``), answered by the compiled core where it is built, else by that method."""
    core = compiled_core()
    if core is None:
        return model.free_function(obstacles)
    ints, floats = model.packed(obstacles, model.pair_arrays)
    checker = core.CollisionChecker(ints, floats)
    batch, one = checker.free, core.free_one

    def free(Q, clearance, self_clearance):
        # squared tests need a positive clearance: 1e-12 m stands for "touching is a collision"
        return batch(Q, max(clearance, 1e-12), max(self_clearance, 1e-12))

    def make_one():  # entry(q, clearance, self_clearance, checker): 1 / 0 / -1 / -2 as the kernel's
        return one, checker

    free.make_one = make_one
    return free
