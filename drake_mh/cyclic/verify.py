"""Independent checks of a cyclic plan with Drake, and its cycle-by-cycle closure.

:func:`verify` recomputes everything from the robot model (principle 4 of DESIGN.md): the end
effector from ``Robot.batch`` (compiled from the Drake plant) and, at a few samples, from
``Robot.fk`` (Drake itself); link positions from the joint frames of the plant
(``Robot.batch.moving_frames``) for the obstacle clearances; joint limits from the URDF.
:func:`cycle_report` gives, over many periods, the same per-cycle figures as the
pseudoinverse baseline (:mod:`drake_mh.cyclic.pinv`): closure and drift in joint space and
joint-limit excess.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.cyclic.obstacles import segment_clearance
from drake_mh.errors import InvalidArgument

__all__ = ["Verification", "verify", "cycle_report", "CycleReport"]


@dataclass(frozen=True)
class Verification:
    """Result of :func:`verify` (all maxima over the samples).

    Attributes:
        ee_error: ``max |p_ee(Drake kernel) - path|`` [m]. drake_fk_error: the same with
            ``Robot.fk`` at a subset of samples [m]. limit_excess: largest excursion beyond the
            URDF limits [rad] (0: within). clearance: smallest link-obstacle clearance with the
            links from the plant's joint frames [m]. closure: ``max |q(cT) - q(0)|`` over the
            cycles [rad]. max_step: largest joint change between consecutive samples [rad]
            (a 2π wrap would show here). success: all within tolerance.
    """

    ee_error: float
    drake_fk_error: float
    limit_excess: float
    clearance: float
    closure: float
    max_step: float
    success: bool


def _robot_links_W(robot, Q) -> np.ndarray:
    """Joint origins and end effector in the plane ``(N, n + 1, 2)`` [m], from the plant."""
    _, p = robot.batch.moving_frames(Q)
    ee = robot.batch.positions(Q)
    return np.concatenate([p[:, :, :2], ee[:, None, :2]], axis=1)


def verify(plan, robot, cycles: int = 1, samples_per_cycle: int = 1000, n_drake: int = 16,
           tol: float = 1e-9) -> Verification:
    """Checks a :class:`~drake_mh.cyclic.planner.CyclicPlan` on a Drake robot.

    Args:
        plan: the plan. robot: the :class:`~drake_mh.robot.Robot` (e.g. ``planar12``).
        cycles, samples_per_cycle: time samples checked.
        n_drake: samples checked with ``Robot.fk`` (Drake's own FK, one call each).
        tol: tolerance of the end-effector and closure checks [m], [rad].

    Raises:
        InvalidArgument: the robot's joint count differs from the plan's.
    """
    if robot.nq != plan.task.n:
        raise InvalidArgument(f"the plan has {plan.task.n} joints but robot {robot.name!r} has {robot.nq}; "
                              "plan on the same arm (CyclicTask.for_robot)")
    t, Q = plan.trajectory(cycles, samples_per_cycle)
    path = plan.task.path.position(t)
    ee = robot.batch.positions(Q)[:, :2]
    ee_error = float(np.max(np.linalg.norm(ee - path, axis=1)))
    idx = np.linspace(0, len(t) - 1, max(2, int(n_drake))).astype(int)
    drake = np.array([robot.fk_drake(Q[i])[:2, 3] for i in idx])
    drake_fk_error = float(np.max(np.linalg.norm(drake - path[idx], axis=1)))
    excess = float(max(np.max(Q - robot.upper), np.max(robot.lower - Q), 0.0))
    links = _robot_links_W(robot, Q)
    clearance = float(np.min(segment_clearance(links, plan.task.obstacles, plan.task.link_radius)))
    q_c = plan.q(np.arange(cycles + 1) * plan.period)
    closure = float(np.max(np.abs(q_c - q_c[0])))
    max_step = float(np.max(np.abs(np.diff(Q, axis=0))))
    success = (ee_error < tol and drake_fk_error < tol and excess <= 1e-12 and clearance > 0.0
               and closure < tol)
    return Verification(ee_error, drake_fk_error, excess, clearance, closure, max_step, bool(success))


@dataclass(frozen=True)
class CycleReport:
    """Per-cycle figures over many periods (proposed method or pseudoinverse baseline).

    Attributes:
        q_start: ``(C + 1, n)`` joint angles at t = cT [rad].
        closure: ``(C,)`` ``max_j |q_j((c+1)T) - q_j(cT)|`` [rad]: non-closure of cycle c.
        drift: ``(C + 1,)`` ``max_j |q_j(cT) - q_j(0)|`` [rad].
        limit_excess: ``(C, n)`` largest excursion beyond each joint's limits in cycle c [rad].
        tracking_error: ``(C,)`` largest end-effector error in cycle c [m].
    """

    q_start: np.ndarray
    closure: np.ndarray
    drift: np.ndarray
    limit_excess: np.ndarray
    tracking_error: np.ndarray


def cycle_report(plan, cycles: int = 500, samples_per_cycle: int = 100, robot=None) -> CycleReport:
    """The plan's figures over ``cycles`` periods (vectorized over all samples).

    Tracking error uses ``robot.batch`` when a robot is given, else the plan's planar FK.
    """
    C, S = int(cycles), int(samples_per_cycle)
    t = (np.arange(C)[:, None] + np.arange(S)[None, :] / S).ravel() * plan.period
    Q = plan.q(t)
    ee = robot.batch.positions(Q)[:, :2] if robot is not None else plan.ee(t)
    err = np.linalg.norm(ee - plan.task.path.position(t), axis=1).reshape(C, S).max(axis=1)
    lower, upper = np.asarray(plan.task.lower), np.asarray(plan.task.upper)
    excess = np.maximum(np.maximum(Q - upper, lower - Q), 0.0).reshape(C, S, -1).max(axis=1)
    q_start = plan.q(np.arange(C + 1) * plan.period)
    closure = np.max(np.abs(np.diff(q_start, axis=0)), axis=1)
    drift = np.max(np.abs(q_start - q_start[0]), axis=1)
    return CycleReport(q_start, closure, drift, excess, err)
