"""Independent checks of an accepted ESM step, with Drake (never with the solver's numbers).

For a step from ``θ_prev`` to ``θ`` :func:`check_step` recomputes

* the joint-limit violation ``max(θ⁻ - θ, θ - θ⁺, 0)`` [rad];
* the velocity violation ``max(|θ - θ_prev| / Δt - s q̇_max, 0)`` [rad/s] (s = velocity_scale);
* the obstacle inequality (eq. (9)) with the Jacobian of each critical point M from Drake's
  ``CalcJacobianTranslationalVelocity`` (not the batched kernel used to build the rows), and
  ``V``, ``V0`` recomputed from the exact distance, the normal and the obstacle velocity:
  largest ``δ θ̇ - (Y V - V0)`` [m/s];
* the largest difference between the kernel's ``δ`` (eq. (8)) and Drake's [m/rad].

The exact clearance at the new time (obstacles moved) is measured by the controller with
``Scene.distances`` (Drake's signed distance) and compared with the threshold there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.reactive.esm.problem import ESMStep

#: default tolerances of :meth:`StepCheck.ok`: [rad], [rad/s], [m/s], [m/rad]
TOLERANCES = {"joint": 1e-9, "velocity": 1e-7, "inequality": 1e-6, "jacobian": 1e-9}


@dataclass(frozen=True)
class StepCheck:
    """Violations of one accepted step (0 or negative inequality margin = satisfied).

    Attributes:
        joint_limit_violation: [rad].
        velocity_violation: [rad/s].
        inequality_violation: largest ``δ θ̇ - rhs`` over the rows [m/s]; ``-inf`` without rows.
        jacobian_error: largest ``|δ_kernel - δ_Drake|`` [m/rad].
    """

    joint_limit_violation: float
    velocity_violation: float
    inequality_violation: float
    jacobian_error: float

    def ok(self, tolerances: dict | None = None) -> bool:
        """Whether every violation is within ``tolerances`` (default :data:`TOLERANCES`)."""
        tol = dict(TOLERANCES, **(tolerances or {}))
        return (self.joint_limit_violation <= tol["joint"] and self.velocity_violation <= tol["velocity"]
                and self.inequality_violation <= tol["inequality"] and self.jacobian_error <= tol["jacobian"])


def drake_point_jacobian(robot, theta, link: str, p_WM) -> np.ndarray:
    """``J_M (3, nq)`` of the point ``p_WM`` fixed on ``link``, from Drake."""
    from pydrake.multibody.tree import JacobianWrtVariable

    plant, context = robot.plant, robot.plant_context
    plant.SetPositions(context, robot.check_q(theta))
    body = plant.GetBodyByName(link)
    X_WB = plant.EvalBodyPoseInWorld(context, body)
    p_BM = X_WB.inverse() @ np.asarray(p_WM, dtype=float)
    return plant.CalcJacobianTranslationalVelocity(context, JacobianWrtVariable.kQDot, body.body_frame(),
                                                   p_BM, plant.world_frame(), plant.world_frame())


def check_step(robot, step: ESMStep, theta) -> StepCheck:
    """Checks ``θ`` against the limits and the obstacle inequalities of ``step`` with Drake."""
    cfg = step.config
    theta = robot.check_q(theta)
    joint = float(max(0.0, np.max(robot.lower - theta), np.max(theta - robot.upper)))
    rate = np.abs(theta - step.theta_prev) / cfg.dt
    velocity = float(max(0.0, np.max(rate - cfg.velocity_scale * robot.velocity_limits)))
    worst, jac_err = -np.inf, 0.0
    for row in step.rows + step.fixed_rows:
        J_M = drake_point_jacobian(robot, step.theta_prev, row.link, row.p_WM)
        delta = -row.u_W @ J_M
        jac_err = max(jac_err, float(np.max(np.abs(delta - row.delta))))
        D = row.distance - cfg.threshold - cfg.buffer
        YV = cfg.Y * (1.0 / (1.0 + np.exp(-abs(D))) - 0.5) * np.sign(D)
        if cfg.step_fraction is not None:
            YV = np.sign(D) * min(abs(YV), cfg.step_fraction * abs(D) / cfg.dt)
        rhs = YV - row.u_W @ row.v_WN
        if any(row is r for r in step.relaxed_rows):     # unsatisfiable: checked against its relaxed bound
            k = next(i for i, r in enumerate(step.rows) if r is row)
            rhs = (step.c[k] - row.delta @ step.theta_prev) / cfg.dt
        if np.linalg.norm(delta) > cfg.fixed_link_tol:  # fixed links: nothing to check
            worst = max(worst, float(delta @ (theta - step.theta_prev) / cfg.dt - rhs))
    return StepCheck(joint, velocity, worst, jac_err)
