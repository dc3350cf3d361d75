"""A scene's obstacles and robot as the compiled planners' kernels take them, bound once per
scene (:meth:`drake_mh.scene.Scene.planner_binding`: rebuilt only after the obstacles change)."""

from __future__ import annotations

import numpy as np

__all__ = ["scene_arguments"]


def scene_arguments(scene) -> tuple:
    """``(ints, floats, v_WO, reach, lower, upper)`` of the scene's current obstacles: its packed
    buffers (:meth:`drake_mh.scene.batch.CollisionModel.packed`, read in compiled code with
    :func:`drake_mh.scene.kernels.unpack`), the obstacles' displacement per lane ``v_WO (K, 3)`` (zero:
    set by segment checks), the sphere model's :attr:`~drake_mh.scene.batch.CollisionModel.reach` and the
    joint limits, float64 and C-contiguous. The same
    tuple until the obstacles change."""
    return scene.planner_binding(scene_arguments, _build)


def _build(scene) -> tuple:
    arrays = scene.obstacle_arrays
    model = scene.collision_model
    ints, floats = model.packed(arrays, model.pair_arrays)
    robot = scene.robot
    return (ints, floats, np.ascontiguousarray(arrays[3], dtype=float), np.ascontiguousarray(model.reach),
            np.ascontiguousarray(robot.lower, dtype=float), np.ascontiguousarray(robot.upper, dtype=float))
