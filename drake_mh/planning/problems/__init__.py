"""Problem sets for point-to-point motion planning: MotionBenchMaker-like scenes, our own pairs.

* :func:`problem_set` — ``count`` problems of one set for a robot, deterministic per ``seed``:
  scenes drawn from primitives like the MotionBenchMaker sets (:mod:`.fixtures`: table pick,
  table under pick, bookshelf small / tall / thin, box, cage), start and goal generated and
  certified free by us (:mod:`.generate`: goals from collision-free IK of pre-grasp poses inside
  the shelf, box or cage).
* :func:`available_problem_sets` — the sets' names and one line each.
* :func:`motionbenchmaker_set` — the *original* MotionBenchMaker Panda problems from a
  downloaded ``vamp-planner`` source distribution (:mod:`.mbm`; never downloaded here).
* :func:`scene_problem_set` — start/goal pairs drawn in the cell of a scene file
  (:mod:`.scene_file`).

Robots: a :class:`drake_mh.robot.Robot`, or a name of :data:`PROBLEM_ROBOTS` — ``"panda"``
(bundled, capsules, no hand), ``"panda_hand"`` (example-robot-data's Panda with its hand,
meshes, fingers locked open, Franka's acceleration and jerk limits), ``"ur5"`` (example-robot-data,
meshes, assumed acceleration limits: :data:`UR5_ACCELERATION`) — or any name or path
:func:`drake_mh.load_robot` takes.

This package is not a planner: :mod:`drake_mh.planning.solve` skips it when it loads the methods.
"""

from drake_mh.planning.problems.generate import ready_configuration, tool_transform
from drake_mh.planning.problems.mbm import MBM_SETS, read_motionbenchmaker
from drake_mh.planning.problems.scene_file import scene_problem_set
from drake_mh.planning.problems.sets import (PROBLEM_ROBOTS, UR5_ACCELERATION, ProblemSet, available_problem_sets,
                                             load_problem_robot, motionbenchmaker_set, problem_set)

__all__ = ["ProblemSet", "problem_set", "available_problem_sets", "motionbenchmaker_set", "scene_problem_set",
           "load_problem_robot", "read_motionbenchmaker", "PROBLEM_ROBOTS", "MBM_SETS", "ready_configuration",
           "tool_transform", "UR5_ACCELERATION"]
