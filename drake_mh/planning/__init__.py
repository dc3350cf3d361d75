"""Point-to-point motion planning among obstacles: one problem, every family, one verification.

* :class:`MotionProblem` (:mod:`.problem`): robot, scene, start, goal (configuration(s) or pose),
  clearance.
* :func:`solve_motion` (:mod:`.solve`): any registered method (:func:`available_motion_methods`),
  verified by :func:`verify_motion` (:mod:`.verify`): limits, goal, the whole motion certified
  collision-free (:mod:`drake_mh.scene.segments`), then retimed and certified.
* One module or folder per method: ``straight`` (baseline), ``rrt_connect`` / ``rrt_connect_smooth``
  (compiled, certified edges), ``mh_<optimizer>`` (metaheuristic via-point optimization, every
  optimizer of the library), ``drake_kto`` / ``drake_kto_warm`` (Drake's
  KinematicTrajectoryOptimization + SNOPT), ``ompl_rrtconnect`` / ``ompl_bitstar`` (OMPL, optional).
"""

from drake_mh.planning.problem import MotionProblem
from drake_mh.planning.result import MotionResult
from drake_mh.planning.solve import (available_motion_methods, get_motion_method, goal_configurations,
                                     prepare_motion_method, register, solve_motion)
from drake_mh.planning.verify import verify_motion

__all__ = ["MotionProblem", "MotionResult", "solve_motion", "available_motion_methods", "verify_motion",
           "goal_configurations", "get_motion_method", "prepare_motion_method", "register"]
