"""Reactive control among moving obstacles: two methods, one subpackage each.

:mod:`drake_mh.reactive.esm` — the ESM paper (Xie et al.): a joint-angle-level control step that
tracks a target, maximizes manipulability and keeps links away from moving obstacles (eqs.
(6)-(11)), solved by AMNN (eqs. (12)-(21), ARO layers), any ``drake_mh.optim`` method, or a
velocity-level QP baseline (OSQP). See ``docs/esm.md``.

:mod:`drake_mh.reactive.follower` — the framework paper (§3.4, Algorithms 1-2): a follower that
regenerates IK for exactly the path points a moved obstacle makes collide, and re-plans the 3·nC
points around path cuts. See ``docs/follower.md``.
"""

from drake_mh.reactive.esm import (
    AMNN,
    SCENARIOS,
    ESMConfig,
    ESMObjective,
    ESMRun,
    ESMScenario,
    ESMStep,
    MetaheuristicSolver,
    MovingObstacle,
    ObstacleRow,
    QPBaseline,
    StepCheck,
    StepSolution,
    StepSolver,
    build_step,
    check_step,
    drake_point_jacobian,
    get_scenario,
    optimal_manipulability,
    optimal_manipulability_along,
    point_jacobian,
    run_esm,
)
from drake_mh.reactive.follower import (
    PATH_EVENT,
    FollowerConfig,
    LocalIKProblem,
    RegeneratingFollower,
    RegenerationEvent,
    ReplanConfig,
    ReplanResult,
    largest_joint_step,
    nearest_free_point,
    replan_points,
    replan_windows,
    run_framework_scenario,
)

__all__ = [
    "AMNN", "ESMConfig", "ESMObjective", "ESMRun", "ESMScenario", "ESMStep", "MetaheuristicSolver",
    "MovingObstacle", "ObstacleRow", "QPBaseline", "SCENARIOS", "StepCheck", "StepSolution", "StepSolver",
    "build_step", "check_step", "drake_point_jacobian", "get_scenario", "optimal_manipulability",
    "optimal_manipulability_along", "point_jacobian", "run_esm",
    "FollowerConfig", "LocalIKProblem", "RegeneratingFollower", "RegenerationEvent", "largest_joint_step",
    "PATH_EVENT", "run_framework_scenario", "ReplanConfig", "ReplanResult", "nearest_free_point",
    "replan_points", "replan_windows",
]
