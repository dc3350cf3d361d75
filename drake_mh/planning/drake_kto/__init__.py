"""``drake_kto``: Drake's ``KinematicTrajectoryOptimization`` + SNOPT as a motion-planning baseline.

* ``drake_kto`` — from the straight joint-space line to the nearest goal configuration;
* ``drake_kto_warm`` — from the ``rrt_connect`` path (its planning time counts in).

How the program is built, solved and turned into waypoints: :mod:`.kto`. The answer is
verified like every planner's (:func:`drake_mh.planning.verify_motion`); the solver's own
success flag is kept in ``info["solver_success"]`` so that a study can count how often it
disagrees with the verified outcome.
"""

from drake_mh.planning.drake_kto.kto import KTOConfig, kto_context, plan_kto, solver_name
from drake_mh.planning.drake_kto.methods import WARM_START, plan, plan_warm

__all__ = ["KTOConfig", "plan_kto", "kto_context", "solver_name", "plan", "plan_warm", "WARM_START"]
