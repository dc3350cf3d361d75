"""Baseline: pseudoinverse-Jacobian resolved rates along the same periodic path.

The cyclic paper's §V.C tracks the leaf with the pseudoinverse Jacobian from the proposed
method's initial configuration for 500 cycles and shows (its Fig. 12) that the joint
trajectories drift and leave eq. (27)'s limits. Here::

    q̇ = J⁺(q) (ṗ_d(t) + K (p_d(t) - p(q))),    J⁺ = Jᵀ (J Jᵀ)⁻¹

with ``J`` the translational x-y rows of Drake's end-effector Jacobian (``Robot.batch``,
compiled from the plant) and ``p`` the end effector from the same kernel. The feedback term
``K`` (closed-loop inverse kinematics) only keeps the end effector on the path against
integration error; it acts in the task space and does not change the null-space drift, which
is the point of the comparison. Integration: classical Runge-Kutta 4 with a fixed step,
vectorized over a batch of initial configurations (one kernel call per stage for the whole
batch). The paper gives neither gain nor step: ``K = 10 1/s`` and 400 steps per period are our
choices (the path error stays below 1e-6 m; see the study).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["PinvResult", "pinv_tracking"]


@dataclass(frozen=True)
class PinvResult:
    """Outcome of :func:`pinv_tracking` for ``B`` initial configurations.

    Attributes:
        t: ``(K,)`` recorded times [s]; q: ``(B, K, n)`` recorded joint angles [rad] (every
            ``record_stride``-th step).
        q_start: ``(B, C + 1, n)`` joint angles at t = cT.
        closure: ``(B, C)`` per-cycle non-closure ``max_j |q((c+1)T) - q(cT)|`` [rad].
        drift: ``(B, C + 1)`` ``max_j |q(cT) - q(0)|`` [rad].
        limit_excess: ``(B, C, n)`` largest excursion beyond each joint's limits per cycle [rad].
        tracking_error: ``(B, C)`` largest end-effector error per cycle [m].
    """

    t: np.ndarray
    q: np.ndarray
    q_start: np.ndarray
    closure: np.ndarray
    drift: np.ndarray
    limit_excess: np.ndarray
    tracking_error: np.ndarray

    def __repr__(self) -> str:
        """A few lines: sizes and the worst figures (not the recorded arrays)."""
        B, C = self.closure.shape
        return (f"PinvResult({B} start(s), {C} cycle(s), {self.q.shape[1]} recorded samples, "
                f"{self.q.shape[2]} joints)\n"
                f"  closure max {self.closure.max(initial=0.0):.3g} rad, drift max "
                f"{self.drift.max(initial=0.0):.3g} rad, limit excess max {self.limit_excess.max(initial=0.0):.3g} "
                f"rad, tracking error max {self.tracking_error.max(initial=0.0):.3g} m")

    __str__ = __repr__


def _rates(robot, path, t: float, Q: np.ndarray, gain: float):
    X, J = robot.batch.fk_jacobian(Q)
    Jxy = J[:, 3:5, :]                                    # (B, 2, n) translational x, y rows
    err = path.position(t)[0] - X[:, :2, 3]               # (B, 2)
    v = path.velocity(t)[0] + gain * err                  # (B, 2)
    A = Jxy @ np.swapaxes(Jxy, 1, 2)                      # (B, 2, 2)
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    y0 = (A[:, 1, 1] * v[:, 0] - A[:, 0, 1] * v[:, 1]) / det
    y1 = (A[:, 0, 0] * v[:, 1] - A[:, 1, 0] * v[:, 0]) / det
    return Jxy[:, 0, :] * y0[:, None] + Jxy[:, 1, :] * y1[:, None], np.linalg.norm(err, axis=1)


def pinv_tracking(robot, path, q0, cycles: int = 500, steps_per_cycle: int = 400, gain: float = 10.0,
                  record_stride: int = 8) -> PinvResult:
    """Tracks ``path`` with pseudoinverse resolved rates for ``cycles`` periods.

    Args:
        robot: a planar :class:`~drake_mh.robot.Robot` moving in world x-y (``planar12``).
        path: a :class:`~drake_mh.cyclic.curves.PeriodicCurve` (positions and velocities).
        q0: ``(n,)`` or ``(B, n)`` initial configurations [rad] (on the path at t = 0).
        cycles: periods to run (the paper: 500).
        steps_per_cycle: RK4 steps per period.
        gain: task-space feedback ``K`` [1/s].
        record_stride: keep every this many steps in :attr:`PinvResult.q`.

    Raises:
        InvalidArgument: bad sizes or non-positive counts.
    """
    Q = np.atleast_2d(np.asarray(q0, dtype=float)).copy()
    if Q.shape[1] != robot.nq:
        raise InvalidArgument(f"q0 must have {robot.nq} joints (robot {robot.name!r}), got shape {Q.shape}")
    if int(cycles) < 1 or int(steps_per_cycle) < 4 or int(record_stride) < 1:
        raise InvalidArgument("cycles >= 1, steps_per_cycle >= 4 and record_stride >= 1 are needed")
    C, S = int(cycles), int(steps_per_cycle)
    B, n = Q.shape
    T = path.period
    h = T / S
    lower, upper = np.asarray(robot.lower), np.asarray(robot.upper)
    q_start = np.empty((B, C + 1, n))
    excess = np.zeros((B, C, n))
    track = np.zeros((B, C))
    rec_t, rec_q = [], []
    q_start[:, 0] = Q
    for c in range(C):
        for s in range(S):
            t = (c * S + s) * h
            if s % record_stride == 0:
                rec_t.append(t)
                rec_q.append(Q.copy())
            k1, e = _rates(robot, path, t, Q, gain)
            track[:, c] = np.maximum(track[:, c], e)
            excess[:, c] = np.maximum(excess[:, c], np.maximum(Q - upper, lower - Q))
            k2, _ = _rates(robot, path, t + h / 2, Q + h / 2 * k1, gain)
            k3, _ = _rates(robot, path, t + h / 2, Q + h / 2 * k2, gain)
            k4, _ = _rates(robot, path, t + h, Q + h * k3, gain)
            Q = Q + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        q_start[:, c + 1] = Q
    rec_t.append(C * T)
    rec_q.append(Q.copy())
    closure = np.max(np.abs(np.diff(q_start, axis=1)), axis=2)
    drift = np.max(np.abs(q_start - q_start[:, :1]), axis=2)
    return PinvResult(np.asarray(rec_t), np.stack(rec_q, axis=1), q_start, closure, drift,
                      np.maximum(excess, 0.0), track)
