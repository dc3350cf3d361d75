"""Inverse kinematics: every metaheuristic, a hybrid and Drake's baselines on one problem.

One :class:`IKProblem` (target position or pose, tolerances, joint limits, obstacles with a
clearance, optional reference configuration and manipulability term) is solved by any method
of :func:`available_ik_methods` through :func:`solve_ik`, and every result is verified the
same way with Drake (:mod:`drake_mh.ik.result`).

Example:
    >>> import drake_mh
    >>> panda = drake_mh.load_robot("panda")
    >>> problem = drake_mh.IKProblem(panda, [0.5, 0.1, 0.4], rpy=[3.14159, 0, 0],
    ...                              position_tolerance=1e-5, orientation_tolerance=1e-5)
    >>> result = drake_mh.solve_ik(problem, "hybrid", seed=0, timeout=0.05)
    >>> result.success
    True

Files: ``problem.py`` (the problem and its vectorized objective), ``result.py`` (IKResult and
Drake verification), ``metaheuristic.py``, ``lm.py`` (batched least-squares kernel),
``hybrid.py``, ``jacobian.py`` (pinv / DLS), ``drake.py`` (SNOPT / IPOPT), ``solve.py``
(the entry point and its table of methods), ``peers.py`` (robotics-toolbox, TRAC-IK and ikpy as
optional peers); ``drake-mh ik`` is :mod:`drake_mh.cli.ik`.
"""

from drake_mh.ik.problem import IKProblem, ReachBound, reach_bound
from drake_mh.ik.result import IKResult, verify
from drake_mh.ik.solve import GRADIENT_METHODS, available_ik_methods, prepare, solve_ik

__all__ = ["IKProblem", "IKResult", "ReachBound", "reach_bound", "solve_ik", "available_ik_methods",
           "verify", "prepare", "GRADIENT_METHODS"]
