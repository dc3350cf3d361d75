"""Reactive control among moving obstacles.

ESM (ESM paper, Xie et al.): a joint-angle-level control step that tracks a target,
maximizes manipulability and keeps links away from moving obstacles (eqs. (6)-(11)), solved
by AMNN (eqs. (12)-(21), ARO layers), any ``drake_mh.optim`` method, or a velocity-level QP
baseline (OSQP). See ``docs/esm.md``.

Framework paper (§3.4, Algorithms 1-2): a follower that regenerates IK for exactly the path
points a moved obstacle makes collide, and re-plans the 3·nC points around path cuts
(:mod:`~drake_mh.reactive.follower`, :mod:`~drake_mh.reactive.replan`). See ``docs/follower.md``.
"""

from drake_mh.reactive.amnn import AMNN
from drake_mh.reactive.esm_config import ESMConfig
from drake_mh.reactive.esm_controller import ESMRun, run_esm
from drake_mh.reactive.esm_optimum import optimal_manipulability, optimal_manipulability_along
from drake_mh.reactive.esm_problem import ESMObjective, ESMStep, ObstacleRow, build_step, point_jacobian
from drake_mh.reactive.esm_scenarios import SCENARIOS, ESMScenario, MovingObstacle, get_scenario
from drake_mh.reactive.esm_solvers import MetaheuristicSolver, StepSolution, StepSolver
from drake_mh.reactive.esm_verify import StepCheck, check_step, drake_point_jacobian
from drake_mh.reactive.follower import (
    FollowerConfig,
    LocalIKProblem,
    RegeneratingFollower,
    RegenerationEvent,
    largest_joint_step,
)
from drake_mh.reactive.framework_scenario import PATH_EVENT, run_framework_scenario
from drake_mh.reactive.qp_baseline import QPBaseline
from drake_mh.reactive.replan import ReplanConfig, ReplanResult, nearest_free_point, replan_points, replan_windows

__all__ = [
    "AMNN", "ESMConfig", "ESMObjective", "ESMRun", "ESMScenario", "ESMStep", "MetaheuristicSolver",
    "MovingObstacle", "ObstacleRow", "QPBaseline", "SCENARIOS", "StepCheck", "StepSolution", "StepSolver",
    "build_step", "check_step", "drake_point_jacobian", "get_scenario", "optimal_manipulability",
    "optimal_manipulability_along", "point_jacobian", "run_esm",
    "FollowerConfig", "LocalIKProblem", "RegeneratingFollower", "RegenerationEvent", "largest_joint_step",
    "PATH_EVENT", "run_framework_scenario", "ReplanConfig", "ReplanResult", "nearest_free_point",
    "replan_points", "replan_windows",
]
