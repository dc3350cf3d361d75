"""Start/goal pairs in the cell a scene file describes (:func:`scene_problem_set`).

A user's cell has no grasp sites to aim at, so the pairs are drawn in joint space: problem ``i``
of a seed draws from ``numpy.random.default_rng([seed, SCENE_CODE, i])`` (problem ``i`` does not
depend on how many are asked for);

* the **start** is the robot's ready configuration
  (:func:`~drake_mh.planning.problems.generate.ready_configuration`) when it is certified free
  in the cell with :data:`~drake_mh.planning.problems.generate.MARGIN` to spare, else the first
  draw that is;
* the **goal** is the first of up to :data:`GOAL_DRAWS` configurations, uniform within the
  joint limits, certified free with that margin whose straight joint-space line from the start
  is *not* certified free (so that a planner has something to do); if every free draw can be
  reached in a straight line, the first free one.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidMotionProblem
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE

__all__ = ["scene_problem_set", "GOAL_DRAWS", "SCENE_CODE"]

GOAL_DRAWS = 256
"""Configurations drawn per problem for its goal (and its start, when the ready one is not free)."""
SCENE_CODE = 101
"""Code of scene-file sets in the random streams (the generated sets use 0, 1, ...)."""


def scene_problem_set(path, robot="panda", count: int = 10, seed: int = 0, clearance: float = 0.0,
                      self_clearance: float = 0.0, self_collision: bool = True, first: int = 0,
                      sphere_tolerance: float = DEFAULT_TOLERANCE, packages=None):
    """``count`` motion problems in the cell of a scene file (module docstring).

    Args:
        path: a scene file (:meth:`drake_mh.scene.Scene.load` reads it; ``packages`` as there).
        robot, count, seed, clearance, self_clearance, self_collision, first, sphere_tolerance:
            as :func:`drake_mh.planning.problems.problem_set` takes them.

    Returns:
        A :class:`~drake_mh.planning.problems.ProblemSet` named ``file/<file name>``; its
        problems share one scene; ``info`` holds ``straight_free`` and ``draws`` (configurations
        drawn for the goal).

    Raises:
        SceneFileNotFound, SceneFileError: the file cannot be read or loaded.
        InvalidMotionProblem: no draw is certified free (the cell fills the robot's reach).
        InvalidArgument: a negative ``count`` or a non-positive ``sphere_tolerance``.
    """
    from drake_mh.planning import MotionProblem
    from drake_mh.planning.problems.sets import ProblemSet, check_count, load_problem_robot
    from drake_mh.planning.problems.generate import (MARGIN, check_sphere_tolerance, new_scene,
                                                     ready_configuration)
    from drake_mh.scene.files import read_scene

    count = check_count(count)
    scene_file = read_scene(path, packages=packages)
    robot = load_problem_robot(robot)
    scene = new_scene(robot, self_collision, check_sphere_tolerance(sphere_tolerance))
    scene.load(scene_file)
    margin = (clearance + MARGIN, self_clearance + MARGIN)
    name = f"file/{Path(path).name}"
    problems, info = [], []
    for index in range(int(first), int(first) + count):
        rng = np.random.default_rng([int(seed), SCENE_CODE, index])
        Q = robot.random_configurations(GOAL_DRAWS, rng)
        free = np.flatnonzero(scene.collision_free(Q, *margin))
        start = ready_configuration(robot)
        if not scene.collision_free(start, *margin) and len(free):
            start, free = Q[free[0]], free[1:]  # the ready configuration collides: the first free draw
        if not len(free):
            raise InvalidMotionProblem(f"{scene_file.path}: none of {GOAL_DRAWS} configurations drawn for problem "
                                       f"{index} is certified free with {MARGIN * 1e3:.0f} mm to spare; does the cell "
                                       f"fill the reach of {robot.name}?")
        k = next((k for k in free if not scene.segment_free(start, Q[k], clearance, self_clearance)), None)
        straight_free = k is None
        k = free[0] if straight_free else k
        problems.append(MotionProblem(robot, scene, start, Q[k], clearance=clearance, self_clearance=self_clearance,
                                      name=f"{name}/{index:04d}"))
        info.append({"straight_free": straight_free, "draws": int(k) + 1, "index": index})
    return ProblemSet(problems, name=name, robot=robot, seed=int(seed), info=info)
