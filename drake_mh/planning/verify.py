"""One verification for every motion planner: the planner's own flags are never read.

A path ``(M, nq)`` succeeds when

1. it is finite, inside the joint limits, starts at ``q_start`` (1e-9 rad) and ends at a goal
   configuration (1e-6 rad) or, for a pose goal, reaches the pose (1 mm / 0.01 rad, Drake FK);
2. the piecewise-linear joint-space motion through it is **certified** collision-free with the
   problem's clearances (:func:`drake_mh.scene.segments.certify_path`: every configuration on
   every segment, not only the waypoints);
3. it retimes into a trajectory certified against the robot's velocity, acceleration and torque
   limits (:func:`drake_mh.trajectories.retime`). toppra's cubic spline through the waypoints
   leaves the straight segments, so it is accepted only where its deviation is covered: per
   piece, the Bernstein bound ``δ_j`` of ``|spline_j - chord_j|`` moves any sphere at most
   ``max_c Σ_j reach[c, j] δ_j`` (:attr:`~drake_mh.scene.batch.CollisionModel.reach`) from the
   certified chord, so the chord's certified clearance minus that is certified for the spline.
   Otherwise ruckig, which stops at every waypoint and follows the straight segments exactly.
"""

from __future__ import annotations

import numpy as np

from drake_mh.planning.problem import POSE_ORIENTATION_TOLERANCE, POSE_POSITION_TOLERANCE
from drake_mh.planning.result import MotionResult

REPORT_TOLERANCE = 1e-3
"""[m] the certified minimum clearance is refined to within this of the smallest value seen."""


def _reaches_goal(problem, q_end: np.ndarray) -> tuple[int | None, str]:
    if problem.goal_pose is None:
        errors = np.max(np.abs(problem.goal_configurations - q_end), axis=1)
        i = int(np.argmin(errors))
        if errors[i] <= 1e-6:
            return i, ""
        return None, f"the path ends {errors[i]:.3g} rad from the nearest goal configuration"
    X_WE = problem.robot.fk_drake(q_end, problem.frame) if problem.frame else problem.robot.fk_drake(q_end)
    X_WG = problem.goal_pose
    position = float(np.linalg.norm(X_WE[:3, 3] - X_WG[:3, 3]))
    cos = (np.trace(X_WG[:3, :3].T @ X_WE[:3, :3]) - 1.0) / 2.0
    angle = float(np.arccos(np.clip(cos, -1.0, 1.0)))
    if position <= POSE_POSITION_TOLERANCE and angle <= POSE_ORIENTATION_TOLERANCE:
        return 0, ""
    return None, f"the path ends {position * 1e3:.2f} mm / {angle:.4f} rad from the goal pose (Drake FK)"


def chord_deviation(spline) -> np.ndarray:
    """``(pieces, nq)`` Bernstein bound of ``max |spline(s) - chord(s)|`` on each cubic piece [rad]."""
    c = spline.c  # (4, pieces, nq), highest power first, local variable s - x_i
    h = np.diff(spline.x)[:, None]
    a3, a2, a1 = c[0] * h ** 3, c[1] * h ** 2, c[2] * h  # monomials in τ = (s - x_i) / h
    slope = a1 + a2 + a3  # the chord: q_i + τ (q_{i+1} - q_i)
    b1 = (a1 - slope) / 3.0  # Bernstein coefficients of spline - chord (b0 = b3 = 0)
    b2 = (2.0 * (a1 - slope) + a2) / 3.0
    return np.maximum(np.abs(b1), np.abs(b2))


def _max_jerk(trajectory) -> float:
    t = np.linspace(trajectory.start_time, trajectory.end_time, 2001)
    try:
        return float(np.max(np.abs(trajectory.jerk(t))))
    except Exception:  # a trajectory without a jerk accessor: report unknown
        return float("nan")


def verify_motion(problem, path, method: str, result: MotionResult | None = None, retime: bool = True) -> MotionResult:
    """Verify ``path`` for ``problem`` and fill a :class:`MotionResult` (see module docstring)."""
    import time

    start = time.perf_counter()
    result = result or MotionResult(method)
    robot, scene = problem.robot, problem.scene
    if path is None:
        result.success, result.message = False, result.message or "no path found"
        return result
    P = np.asarray(path, dtype=float)
    if P.ndim != 2 or P.shape[1] != robot.nq or len(P) < 1 or not np.all(np.isfinite(P)):
        result.success, result.message = False, f"the method returned an invalid path of shape {P.shape}"
        return result
    if len(P) == 1:
        P = np.vstack([P, P])
    result.path = P
    result.path_length = float(np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1)))
    outside = (P < robot.lower - 1e-9) | (P > robot.upper + 1e-9)
    if np.any(outside):
        row, j = np.argwhere(outside)[0]
        result.success, result.message = False, f"waypoint {row} leaves joint {robot.joint_names[j]!r}'s limits"
        return result
    if np.max(np.abs(P[0] - problem.q_start)) > 1e-9:
        result.success, result.message = False, "the path does not start at q_start"
        return result
    goal_index, why = _reaches_goal(problem, P[-1])
    if goal_index is None:
        result.success, result.message = False, why
        return result
    result.goal_index = goal_index if result.goal_index is None else result.goal_index
    cert = scene.certify_path(P, problem.clearance, problem.self_clearance, tolerance=REPORT_TOLERANCE)
    result.info["certificate"] = cert
    if not cert.certified:
        result.success = False
        result.message = f"motion not certified collision-free: segment {cert.first_failure}: " \
                         f"{cert.segments.reason(cert.first_failure)}"
        result.verify_time = time.perf_counter() - start
        return result
    result.min_clearance = cert.min_clearance
    result.success, result.message = True, "certified"
    if retime:
        trajectory, message = _retime(problem, P, cert)
        if trajectory is None:
            result.success, result.message = False, message
        else:
            result.trajectory, result.duration = trajectory, float(trajectory.end_time - trajectory.start_time)
            result.max_jerk = _max_jerk(trajectory)
            result.min_clearance = trajectory.info.get("certified_clearance", result.min_clearance)
            result.message = f"certified; retimed with {trajectory.method}"
    result.verify_time = time.perf_counter() - start
    return result


def _retime(problem, P: np.ndarray, cert) -> tuple[object, str]:
    """toppra where its spline is certified clear, else ruckig (straight segments)."""
    from drake_mh.errors import DrakeMhError
    from drake_mh.trajectories import retime

    robot, scene = problem.robot, problem.scene
    keep = np.r_[True, np.any(np.abs(np.diff(P, axis=0)) > 1e-12, axis=1)]  # repeated rows break splines
    W = P[keep]
    if len(W) < 2:
        W = np.vstack([P[0], P[0] + 1e-9 * (robot.upper - robot.lower)])
        W[1] = np.minimum(W[1], robot.upper)
    try:
        trajectory = retime(W, robot, "toppra")
        spline = trajectory.path
        knots = spline(spline.x)  # waypoints and inserted chord midpoints: all on the certified path
        chords = scene.certify_path(knots, problem.clearance, problem.self_clearance, tolerance=REPORT_TOLERANCE)
        if chords.certified:
            reach = scene.collision_model.reach
            deviation = chord_deviation(spline)  # (pieces, nq)
            shift = np.max(deviation @ reach.T, axis=1)  # (pieces,) largest sphere displacement
            clear = chords.segments.lower - shift
            clear_self = chords.segments.lower_self - shift
            if np.all(clear >= problem.clearance) and np.all(clear_self >= problem.self_clearance):
                trajectory.info["certified_clearance"] = float(np.min(clear))
                return trajectory, ""
    except DrakeMhError:
        pass
    try:
        trajectory = retime(W, robot, "ruckig")
        trajectory.info["certified_clearance"] = cert.min_clearance  # exactly the certified segments
        return trajectory, ""
    except DrakeMhError as exc:
        return None, f"certified path, but no certified trajectory: {exc}"
