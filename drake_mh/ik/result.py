"""IK results and their verification with Drake, independent of the solver.

Every IK method returns a configuration; :func:`verify` turns it into an :class:`IKResult`
whose ``success`` is recomputed here with Drake — forward kinematics of the plant
(``Robot.fk``), Drake's exact signed distances (``Scene.min_distance``) and the joint limits —
against the problem's tolerances. A solver's own fitness or status is never trusted
(DESIGN.md principle 4): a target reached in position but missed in orientation, a
configuration outside the joint limits or one closer to an obstacle than the clearance is a
failure whatever the solver said.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from drake_mh.ik.problem import IKProblem

_SQRT8 = 2.0 * math.sqrt(2.0)

__all__ = ["IKResult", "verify", "LIMIT_TOLERANCE"]

#: [rad or m] slack on the joint limits in verification: none beyond round-off
LIMIT_TOLERANCE = 1e-12


@dataclass(frozen=True)
class IKResult:
    """Outcome of one IK solve, verified with Drake.

    Attributes:
        q: ``(nq,)`` the returned configuration (the best found when unsuccessful).
        success: position error <= tolerance, orientation error <= tolerance (full pose),
            within the joint limits, and exact clearance >= the problem's clearance —
            all recomputed with Drake.
        position_error: ``||p_WT - p_WE(q)||`` [m] from Drake's FK.
        orientation_error: rotation angle between ``R_WT`` and ``R_WE(q)`` [rad]; 0 for a
            position-only target.
        min_distance: smallest exact signed distance to the obstacles [m] (Drake); ``inf``
            without obstacles.
        within_limits: ``q`` respects the joint limits.
        time: wall-clock time of the solve [s] (verification included).
        nfe: configurations evaluated by the method (objective or FK + Jacobian
            evaluations); 0 for Drake's solvers, which do not report it (see ``attempts``).
        method: the method name.
        message: why it ended / why it failed, in words.
        attempts: local-solver starts (restarts), where the method has them.
        history_nfe, history_best: ``(K,)`` best-so-far objective against evaluations
            (metaheuristics; empty otherwise).
        prepare_time: [s] spent before the solve's clock started, loading what the method
            needs (compiled kernels, Drake programs, the reach bound; see
            :func:`drake_mh.ik.prepare`); 0 when everything was loaded already. Not part of
            ``time``, so a ``timeout`` measures solving only.
    """

    q: np.ndarray
    success: bool
    position_error: float
    orientation_error: float
    min_distance: float
    within_limits: bool
    time: float
    nfe: int
    method: str
    message: str
    attempts: int = 0
    history_nfe: np.ndarray = field(default_factory=lambda: np.zeros(0))
    history_best: np.ndarray = field(default_factory=lambda: np.zeros(0))
    prepare_time: float = 0.0

    def to_dict(self) -> dict:
        """JSON-friendly dict (``q`` as a list, histories left out)."""
        return {
            "q": [float(v) for v in self.q],
            "success": bool(self.success),
            "position_error": float(self.position_error),
            "orientation_error": float(self.orientation_error),
            "min_distance": None if not np.isfinite(self.min_distance) else float(self.min_distance),
            "within_limits": bool(self.within_limits),
            "time": float(self.time),
            "nfe": int(self.nfe),
            "method": self.method,
            "message": self.message,
            "attempts": int(self.attempts),
            "prepare_time": float(self.prepare_time),
        }


def check(problem: IKProblem, q) -> tuple[bool, float, float, float, bool, str]:
    """Drake's verdict on ``q``: ``(success, e_p [m], θ [rad], min distance [m], within limits, why)``.

    The pose comes from Drake's FK of the plant (``Robot.fk``), the distance from Drake's exact
    signed distances; the arithmetic on the (4, 4) pose is scalar Python (a few µs where
    numpy's per-call overhead cost ~40 µs: this check is part of every solve's time).
    """
    robot = problem.robot
    X_WE = robot.fk_drake(q, problem.frame)  # checks q (shape, finite) first
    q = np.asarray(q, dtype=float)
    (r00, r01, r02, x), (r10, r11, r12, y), (r20, r21, r22, z), _ = X_WE.tolist()
    px, py, pz = problem.p_WT.tolist()
    e_p = math.sqrt((x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2)
    if problem.R_WT is None:
        e_o = 0.0
    else:  # rotation_angle: ||R_WE - R_WT||_F = 2√2 sin(θ/2)
        (t00, t01, t02), (t10, t11, t12), (t20, t21, t22) = problem.R_WT.tolist()
        d2 = ((r00 - t00) ** 2 + (r01 - t01) ** 2 + (r02 - t02) ** 2 + (r10 - t10) ** 2 + (r11 - t11) ** 2
              + (r12 - t12) ** 2 + (r20 - t20) ** 2 + (r21 - t21) ** 2 + (r22 - t22) ** 2)
        e_o = 2.0 * math.asin(min(math.sqrt(d2) / _SQRT8, 1.0))
    lower, upper = robot.lower, robot.upper
    within = all(lo - LIMIT_TOLERANCE <= v <= hi + LIMIT_TOLERANCE
                 for v, lo, hi in zip(q.tolist(), lower.tolist(), upper.tolist())) or \
        robot.within_limits(q, tol=LIMIT_TOLERANCE)  # continuous joints may leave [-π, π]
    distance = problem.scene.min_distance(q) if problem.has_obstacles else math.inf
    if e_p <= problem.position_tolerance and e_o <= problem.orientation_tolerance and within and \
            distance >= problem.clearance:
        return True, e_p, e_o, float(distance), within, ""
    reasons = []
    if e_p > problem.position_tolerance:
        reasons.append(f"position error {e_p:.3g} m > {problem.position_tolerance:g} m")
    if e_o > problem.orientation_tolerance:
        reasons.append(f"orientation error {e_o:.3g} rad > {problem.orientation_tolerance:g} rad")
    if not within:
        bad = [n for n, v, lo, hi, c in zip(robot.joint_names, q, lower, upper, robot.continuous)
               if not c and not (lo - LIMIT_TOLERANCE <= v <= hi + LIMIT_TOLERANCE)]
        reasons.append(f"outside the joint limits at {bad}")
    if distance < problem.clearance:
        reasons.append(f"exact clearance {distance:.3g} m < {problem.clearance:g} m")
    return not reasons, e_p, e_o, float(distance), within, "; ".join(reasons)


def verify(problem: IKProblem, q, *, method: str, start: float, nfe: int, message: str = "",
           attempts: int = 0, history=None) -> IKResult:
    """Verifies ``q`` with Drake and packs an :class:`IKResult`.

    Args:
        problem: the problem.
        q: ``(nq,)`` configuration returned by the method.
        method: method name.
        start: ``time.perf_counter()`` at the start of the solve (``time`` includes this check).
        nfe: evaluations used.
        message: the method's own account (kept, followed by Drake's verdict on failure).
        attempts: local-solver starts.
        history: optional ``(K, 2)`` array of ``(nfe, best f)`` rows.
    """
    ok, e_p, e_o, distance, within, why = check(problem, q)
    text = message if ok else (f"{message}; " if message else "") + f"not verified: {why}"
    if history is None:
        h_nfe, h_best = np.zeros(0), np.zeros(0)
    else:
        history = np.asarray(history, dtype=float).reshape(-1, 2)
        h_nfe, h_best = history[:, 0].copy(), history[:, 1].copy()
    return IKResult(q=np.array(q, dtype=float), success=ok, position_error=e_p, orientation_error=e_o,
                    min_distance=distance, within_limits=within, time=time.perf_counter() - start,
                    nfe=int(nfe), method=method, message=text or "verified", attempts=int(attempts),
                    history_nfe=h_nfe, history_best=h_best)
