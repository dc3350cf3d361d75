"""The framework paper's regenerating path follower among moving obstacles (§3.4, Algorithms 1-2).

The arm follows a joint solution of a Cartesian path (IK at every point, §3.3). When an obstacle
moves, the follower regenerates IK for exactly the remaining path points whose configurations
now collide (§3.4.1), and where the obstacle cuts the path itself it re-plans the 3·nC points
around each cut with the metaheuristic and solves them again (§3.4.2, Algorithm 2). Any IK
method of :func:`drake_mh.ik.available_ik_methods` can be used. See ``docs/follower.md``.

Files:

* :mod:`.follower` — :class:`RegeneratingFollower`, :class:`FollowerConfig`,
  :class:`RegenerationEvent` (§3.4.1, and §3.4.2 through :mod:`.replan`);
* :mod:`.replan` — Algorithm 2: colliding path points, their windows, nearest free points;
* :mod:`.motion`, :mod:`.detour` — not in the paper: the motion between two points certified
  collision-free, a detour through via configurations where the straight line is not;
* :mod:`.scenario` — the paper's dynamic-obstacle scenario (§4, Tables 2-3) as one function,
  :func:`run_framework_scenario`.
"""

from drake_mh.reactive.follower.detour import ChainCertificate, Detour, DetourConfig, certify_chains, find_detour
from drake_mh.reactive.follower.follower import (
    FollowerConfig,
    LocalIKProblem,
    RegeneratingFollower,
    RegenerationEvent,
    largest_joint_step,
    revolute_mask,
    wrap_toward,
)
from drake_mh.reactive.follower.motion import DetourRecord
from drake_mh.reactive.follower.replan import (
    ReplanConfig,
    ReplanResult,
    colliding_path_points,
    collision_runs,
    nearest_free_point,
    obstacle_circumradius,
    path_point_clearance,
    replan_points,
    replan_windows,
)
from drake_mh.reactive.follower.scenario import (
    MOVE_AT,
    OBSTACLE_MOVED,
    OBSTACLE_RADIUS,
    OBSTACLE_START,
    PATH_EVENT,
    run_framework_scenario,
)

__all__ = [
    "FollowerConfig", "LocalIKProblem", "RegeneratingFollower", "RegenerationEvent", "largest_joint_step",
    "revolute_mask", "wrap_toward",
    "ReplanConfig", "ReplanResult", "colliding_path_points", "collision_runs", "nearest_free_point",
    "obstacle_circumradius", "path_point_clearance", "replan_points", "replan_windows",
    "Detour", "DetourConfig", "DetourRecord", "ChainCertificate", "certify_chains", "find_detour",
    "MOVE_AT", "OBSTACLE_MOVED", "OBSTACLE_RADIUS", "OBSTACLE_START", "PATH_EVENT", "run_framework_scenario",
]
