"""Continuity of IK solutions from one path point to the next.

A position target leaves a 6- or 7-joint arm a whole self-motion manifold of solutions (and
several IK branches); solving each point of a path on its own lets the arm jump between them.
:func:`solve_near` solves one point *near a reference configuration* (usually the previous
point's solution), as :func:`drake_mh.paths.ik_along_path` and the regenerating follower
(:mod:`drake_mh.reactive.follower`, framework paper §3.4) both need:

1. **Search boxes that widen on failure.** Attempt ``a`` searches within
   ``q_ref ± search_radii[a]`` intersected with the joint limits (:class:`LocalIKProblem`:
   every :func:`~drake_mh.ik.solve_ik` method searches within ``problem.lower/upper``), with
   the displacement penalty ``ref_weight · ||q − q_ref||``; a ``None`` radius searches the
   whole range *without* the reference (no penalty, no start at or pull toward ``q_ref``:
   feasibility over continuity — the hybrid's null-space pull toward a blocked ``q_ref`` made
   every converged candidate collide). Default ``(0.3, 1.0,
   None)``: a first-attempt success bounds every joint step by 0.3 rad — also of joints the
   task does not see.
2. **Tidying that does not change what the task sees** (:func:`tidy_toward`): revolute joints
   are shifted by 2π toward the reference (:func:`wrap_toward`, same pose), and joints whose
   reset to the reference keeps the target and the clearance are reset (the 6-DOF arm's last
   joint does not move its tool point; a whole-range search left it anywhere in ±2π, a 6 rad
   step). Drake verifies the tidied configuration again; if it does not pass, the solver's
   own result is kept.

The best attempt is returned (verified ones first, then the smallest position error plus
missing clearance).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from drake_mh.ik.problem import IKProblem

__all__ = ["LocalIKProblem", "revolute_mask", "wrap_toward", "tidy_toward", "solve_near", "DEFAULT_SEARCH_RADII"]

#: [rad] search boxes around the reference, widened on failure; None = the whole range, no penalty
DEFAULT_SEARCH_RADII = (0.3, 1.0, None)


@dataclass(frozen=True, eq=False)
class LocalIKProblem(IKProblem):
    """An :class:`~drake_mh.ik.IKProblem` whose search box is ``q_ref ± search_radius`` within the limits.

    Every method of :func:`~drake_mh.ik.solve_ik` searches within ``problem.lower`` /
    ``problem.upper`` (metaheuristic bounds, hybrid and Jacobian restarts and clamps);
    verification still uses the robot's own limits. ``search_radius=None``: the limits.
    Drake's ``InverseKinematics`` keeps the robot's limits but starts at ``q_ref``.
    """

    search_radius: float | None = None

    @property
    def lower(self) -> np.ndarray:
        """``(nq,)`` lower end of the search box [rad]."""
        if self.search_radius is None or self.q_ref is None:
            return self.robot.lower
        return np.maximum(self.robot.lower, self.q_ref - self.search_radius)

    @property
    def upper(self) -> np.ndarray:
        """``(nq,)`` upper end of the search box [rad]."""
        if self.search_radius is None or self.q_ref is None:
            return self.robot.upper
        return np.minimum(self.robot.upper, self.q_ref + self.search_radius)


def revolute_mask(robot) -> np.ndarray:
    """``(nq,)`` whether each joint is revolute (a 2π shift leaves its pose unchanged)."""
    return np.array([robot.plant.GetJointByName(n).type_name() == "revolute" for n in robot.joint_names])


def wrap_toward(robot, q, q_ref) -> np.ndarray:
    """``q`` with each revolute joint shifted by a multiple of 2π to the value nearest ``q_ref`` within the limits.

    The same pose (forward kinematics and collision geometry are unchanged); joints with a
    range wider than 2π (the 6-DOF arm: ±260°, ±360°) otherwise start a path near a limit
    and must later turn back a full revolution (measured: a 6.2 rad step on joint 3).
    """
    q = np.array(q, dtype=float)
    revolute = revolute_mask(robot)
    for j in np.flatnonzero(revolute & ~robot.continuous):
        candidates = q[j] + 2.0 * np.pi * np.arange(-3, 4)
        ok = candidates[(candidates >= robot.lower[j]) & (candidates <= robot.upper[j])]
        if ok.size:
            q[j] = ok[np.argmin(np.abs(ok - q_ref[j]))]
    return q


def tidy_toward(problem: IKProblem, result, q_ref):
    """Moves a verified IK result toward ``q_ref`` without changing what the task sees.

    1. Revolute joints are shifted by 2π toward ``q_ref`` (the range centre when ``q_ref``
       is ``None``) (:func:`wrap_toward`: same pose).
    2. With a ``q_ref``, each joint (largest change first) whose reset to ``q_ref`` keeps the
       pose within the tolerances (batched FK) and the sphere-model clearance is reset.

    Returns:
        The tidied result verified by Drake, or ``result`` itself when nothing changed or
        Drake does not verify the tidied configuration.
    """
    import time as _time

    from drake_mh.ik import verify

    robot = problem.robot
    ref = 0.5 * (robot.lower + robot.upper) if q_ref is None else q_ref
    q = wrap_toward(robot, result.q, ref)
    changed = bool(np.any(q != result.q))
    if q_ref is not None:
        for j in np.argsort(-np.abs(q - q_ref)):
            if abs(q[j] - q_ref[j]) < 1e-9:
                break
            trial = q.copy()
            trial[j] = q_ref[j]
            e_p, e_o = problem.pose_errors(trial[None])
            if e_p[0] > problem.position_tolerance or e_o[0] > problem.orientation_tolerance:
                continue
            if problem.has_obstacles and problem.scene.batch_min_distance(trial[None])[0] < problem.clearance:
                continue
            q, changed = trial, True
    if not changed:
        return result
    start = _time.perf_counter() - result.time
    tidy = verify(problem, q, method=result.method, start=start, nfe=result.nfe,
                  message=result.message + "; tidied (2π shifts, unseen joints kept)")
    return tidy if tidy.success else result


def solve_near(robot, target, q_ref, method: str, seed_of: Callable[[int], int], *,
               search_radii=DEFAULT_SEARCH_RADII, ref_weight: float = 0.05, position_tolerance: float = 1e-3,
               scene=None, clearance: float = 0.0, budget: int | None = None, timeout: float | None = None,
               x0=(), params: dict | None = None):
    """Position IK for ``target`` near ``q_ref``: widening search boxes, then tidying (module docstring).

    Args:
        robot: the :class:`~drake_mh.robot.Robot`.
        target: ``(3,)`` tool position [m].
        q_ref: ``(nq,)`` reference configuration [rad], or ``None`` (a free search: every
            attempt covers the whole range, only the seed changes).
        method: any name of :func:`drake_mh.ik.available_ik_methods`.
        seed_of: ``seed_of(attempt) -> int``, the seed of each attempt.
        search_radii: one attempt per entry [rad]; ``None`` = the whole range without penalty.
        ref_weight: [m/rad] displacement penalty of the local attempts.
        position_tolerance, scene, clearance: as in :class:`~drake_mh.ik.IKProblem`.
        budget, timeout: per attempt, as in :func:`~drake_mh.ik.solve_ik`.
        x0: configurations put into a metaheuristic's initial population (clipped into each
            attempt's box; ignored by the gradient methods, which start from ``q_ref``).
        params: optimizer options for the metaheuristics.

    Returns:
        ``(best IKResult, evaluations spent over all attempts)``.
    """
    from drake_mh.ik import GRADIENT_METHODS, solve_ik

    extra = dict(params or {})
    seeds = [np.asarray(q, dtype=float) for q in x0 if q is not None]
    use_x0 = method.lower() not in GRADIENT_METHODS and bool(seeds)
    best, nfe = None, 0
    for attempt, radius in enumerate(search_radii):
        local = q_ref is not None and radius is not None
        problem = LocalIKProblem(robot, target, position_tolerance=position_tolerance, scene=scene,
                                 clearance=clearance, q_ref=q_ref if local else None,
                                 ref_weight=ref_weight if local else 0.0,
                                 search_radius=radius if local else None)
        if use_x0:
            extra["x0"] = np.clip(np.array(seeds), problem.lower, problem.upper)
        res = solve_ik(problem, method, seed=seed_of(attempt), budget=budget, timeout=timeout, **extra)
        nfe += int(res.nfe)
        if res.success:
            res = tidy_toward(problem, res, q_ref)
        score = (not res.success, res.position_error + max(0.0, clearance - res.min_distance))
        if best is None or score < best[0]:
            best = (score, res)
        if res.success:
            break
    return best[1], nfe
