"""Point-to-point motion planning among obstacles: one problem, every family, one verification.

* :class:`MotionProblem` (:mod:`.problem`): robot, scene, start, goal (configuration(s) or pose),
  clearance.
* :func:`solve_motion` (:mod:`.solve`): any registered method (:func:`available_motion_methods`),
  verified by :func:`verify_motion` (:mod:`.verify`): limits, goal, the whole motion certified
  collision-free (:mod:`drake_mh.scene.segments`), then retimed and certified.
* One module or folder per method: ``straight`` (baseline), and the planners beside it.
"""

from drake_mh.planning.problem import MotionProblem
from drake_mh.planning.result import MotionResult
from drake_mh.planning.solve import available_motion_methods, goal_configurations, register, solve_motion
from drake_mh.planning.verify import verify_motion

__all__ = ["MotionProblem", "MotionResult", "solve_motion", "available_motion_methods", "verify_motion",
           "goal_configurations", "register"]
