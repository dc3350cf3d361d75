"""Inverse kinematics along a Cartesian path, with continuity (framework paper §3.3).

"Once the path is generated, the joint angles required to reach each and every point in the
path is obtained using the inverse kinematics solver" (framework paper §3.3, Algorithm 1 per
point). Solving every point independently lets a redundant arm jump between IK branches from
one point to the next; here each point after the first is solved

* **warm-started** from the previous point's solution (``q_ref`` is the first start of the
  gradient methods and of the hybrid's population; the metaheuristics get it as ``x0``, one
  individual of their initial population), and
* with a **joint-displacement penalty** ``ref_weight · ||q - q_prev||`` in the objective
  (:class:`drake_mh.ik.IKProblem`'s ``q_ref``/``ref_weight``). The position term is a norm, not
  its square, so a small weight picks the closest solution on the target's self-motion
  manifold without pulling the end effector off the target;
* within **search boxes that widen on failure** (``q_prev ± 0.3 rad``, ``± 1 rad``, then the
  whole range without penalty) and **tidied** (2π shifts toward ``q_prev``, joints the task
  does not see kept) — :func:`drake_mh.paths.continuity.solve_near`, shared with the
  regenerating follower. (Without them Drake's SNOPT and the hybrid, which only start near
  ``q_prev``, were measured to jump 4–6 rad on the 6-DOF arm's ±2π joints.)

Any method of :func:`drake_mh.ik.available_ik_methods` can be used. The result reports the
largest joint step between consecutive points (where it happens and on which joint).

With a ``scene`` the *motion* is certified too, not only its points: the piecewise-linear
joint-space motion through the solutions is checked with
:meth:`drake_mh.scene.Scene.certify_path` (the conservative sphere model, every configuration on
every segment; with the path's times the obstacles move with their velocities), and
``all_success`` requires it. A segment that is not certified is reported (which, and why), not
repaired: :class:`drake_mh.reactive.follower.RegeneratingFollower` detours around it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import check_seed
from drake_mh.paths.continuity import DEFAULT_SEARCH_RADII, solve_near

__all__ = ["JointPath", "ik_along_path", "joint_steps", "certify_motion"]


@dataclass(frozen=True)
class JointPath:
    """Joint configurations along a Cartesian path.

    Attributes:
        q: ``(N, nq)`` configurations [rad].
        success: ``(N,)`` each point's verified IK success (Drake FK, limits, obstacles).
        position_error: ``(N,)`` [m] from Drake's FK.
        steps: ``(N-1,)`` largest absolute joint change between consecutive points [rad].
        max_step: ``max(steps)`` [rad]; ``max_step_index`` k: between points k and k+1;
            ``max_step_joint``: the joint name.
        time: total solve time [s]; nfe: total evaluations; method: the IK method.
        motion_certified: with a scene, whether the motion through ``q`` (straight in joint space
            between consecutive points) is certified collision-free for every configuration on
            it; ``None`` without a scene.
        motion_min_clearance: its certified lower bound of the obstacle clearance [m] (within
            1 mm of the smallest value seen; NaN if not certified or without a scene).
        motion_first_failure: first segment k (point k -> k + 1) not certified (``None`` if none).
        motion_failure_reason: why (``""`` if none).
    """

    q: np.ndarray
    success: np.ndarray
    position_error: np.ndarray
    steps: np.ndarray
    max_step: float
    max_step_index: int
    max_step_joint: str
    time: float
    nfe: int
    method: str
    motion_certified: bool | None = None
    motion_min_clearance: float = float("nan")
    motion_first_failure: int | None = None
    motion_failure_reason: str = ""

    @property
    def all_success(self) -> bool:
        """Whether every point was solved and, with a scene, the motion between them is certified."""
        return bool(np.all(self.success)) and self.motion_certified is not False


def joint_steps(Q) -> np.ndarray:
    """Largest absolute joint change between consecutive rows of ``Q (N, nq)``: ``(N-1,)`` [rad]."""
    Q = np.asarray(Q, dtype=float)
    return np.abs(np.diff(Q, axis=0)).max(axis=1) if len(Q) > 1 else np.zeros(0)


def ik_along_path(robot, points, method: str = "hybrid", seed: int = 0, *, q_start=None,
                  ref_weight: float = 0.01, budget: int | None = None, timeout: float | None = None,
                  first_budget: int | None = None, position_tolerance: float = 1e-3, scene=None,
                  clearance: float = 0.0, search_radii=DEFAULT_SEARCH_RADII, progress=None,
                  motion_clearance: float = 0.0, times=None, **params) -> JointPath:
    """Solve position IK at every point of a path, each warm-started from the previous solution.

    Args:
        robot: the :class:`~drake_mh.robot.Robot`.
        points: ``(N, 3)`` end-effector positions [m] (e.g. ``trapezoidal_path(...).points``) or a
            :class:`~drake_mh.paths.cartesian.CartesianPath` (its ``times`` are then used).
        method: any IK method (``"hybrid"``, ``"pso"``, ``"drake_snopt"`` ...).
        seed: base seed; point k uses an independent stream spawned from it.
        q_start: configuration near which to solve the first point (``None``: a free search).
        ref_weight: joint-displacement penalty [m/rad] from the second point on (0: none).
        budget, timeout: per point, as in :func:`drake_mh.ik.solve_ik`.
        first_budget: budget of the first point (default ``budget``): it has no warm start.
        position_tolerance: [m] (default 1 mm, the framework paper's position-only IK).
        scene, clearance: obstacles, as in :class:`drake_mh.ik.IKProblem`.
        search_radii: search boxes around the previous solution [rad], one attempt each,
            ``None`` = the whole range (:func:`~drake_mh.paths.continuity.solve_near`).
        progress: ``progress(k, N)`` called after each point.
        motion_clearance: [m] certified along the motion between the points (default 0:
            collision-free; the points keep ``clearance`` by Drake's exact distance).
        times: ``(N,)`` [s] when the tool is at each point (default ``points.times`` if any):
            obstacles with a velocity move with it during the certified motion; without times
            the motion is certified against the obstacles where they are, like the points.
        **params: optimizer options for the metaheuristics.

    Returns:
        :class:`JointPath`.

    Raises:
        InvalidArgument: points of the wrong shape, a negative ``ref_weight``, bad ``search_radii``.
    """
    P = np.asarray(getattr(points, "points", points), dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 1 or not np.all(np.isfinite(P)):
        raise InvalidArgument(f"points must be a finite (N, 3) array of positions, got shape {P.shape}")
    if not (ref_weight >= 0):
        raise InvalidArgument(f"ref_weight must be >= 0, got {ref_weight!r}")
    radii = tuple(search_radii) if isinstance(search_radii, (tuple, list)) else ()
    if not radii or not all(r is None or (isinstance(r, (int, float)) and np.isfinite(r) and r > 0) for r in radii):
        raise InvalidArgument(f"search_radii must be a non-empty tuple of positive radii [rad] or None "
                              f"(whole joint range), got {search_radii!r}")
    seeds = np.random.SeedSequence(check_seed(seed)).spawn(len(P))
    Q = np.zeros((len(P), robot.nq))
    ok = np.zeros(len(P), dtype=bool)
    err = np.zeros(len(P))
    nfe = 0
    start = time.perf_counter()
    q_prev = None if q_start is None else robot.check_q(q_start, "q_start")
    for k, target in enumerate(P):
        def seed_of(attempt: int, k=k) -> int:
            return int(seeds[k].generate_state(attempt + 1)[attempt])

        first = k == 0
        res, used = solve_near(robot, target, q_prev, method, seed_of, search_radii=radii,
                               ref_weight=0.0 if first else ref_weight, position_tolerance=position_tolerance,
                               scene=scene, clearance=clearance,
                               budget=first_budget if (first and first_budget is not None) else budget,
                               timeout=timeout, x0=[q_prev], params=params)
        Q[k], ok[k], err[k] = res.q, res.success, res.position_error
        nfe += used
        q_prev = res.q
        if progress is not None:
            progress(k + 1, len(P))
    steps = joint_steps(Q)
    i = int(np.argmax(steps)) if len(steps) else 0
    j = int(np.argmax(np.abs(Q[i + 1] - Q[i]))) if len(steps) else 0
    motion = {}
    if scene is not None:
        motion = certify_motion(scene, Q, motion_clearance, getattr(points, "times", None) if times is None
                                else times)
    return JointPath(Q, ok, err, steps, float(steps[i]) if len(steps) else 0.0, i, robot.joint_names[j],
                     time.perf_counter() - start, nfe, method, **motion)


def certify_motion(scene, Q, clearance: float = 0.0, times=None, tolerance: float = 1e-3) -> dict:
    """The verdict on the piecewise-linear joint-space motion through ``Q (N, nq)`` as
    :class:`JointPath`'s ``motion_*`` fields (:meth:`drake_mh.scene.Scene.certify_path`).

    Args:
        scene: the scene (obstacles where they are when the motion starts).
        Q: ``(N, nq)`` configurations [rad].
        clearance: required along the motion [m].
        times: ``(N,)`` [s]; used where an obstacle has a velocity (``None``: they stand still).
        tolerance: of the reported lower bound [m].

    Raises:
        InvalidArgument: times of the wrong shape or decreasing.
    """
    if not scene.obstacles and not getattr(scene, "self_collision", False):
        return {"motion_certified": True, "motion_min_clearance": float("inf")}
    durations = None
    if times is not None and len(Q) > 1 and any(np.any(o.velocity_W != 0) for o in scene.obstacles.values()):
        t = np.asarray(times, dtype=float).reshape(-1)
        if t.shape != (len(Q),) or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
            raise InvalidArgument(f"times must be {len(Q)} finite non-decreasing seconds, one per point")
        durations = np.diff(t)
    cert = scene.certify_path(Q, clearance, tolerance=tolerance, durations=durations)
    first = cert.first_failure
    return {"motion_certified": bool(cert.certified), "motion_min_clearance": float(cert.min_clearance),
            "motion_first_failure": first,
            "motion_failure_reason": "" if first is None else f"segment {first}: {cert.segments.reason(first)}"}
