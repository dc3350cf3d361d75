"""Gradient baseline of the ESM step: a velocity-level QP solved by OSQP through pydrake.

Variables: the joint increment ``Δ = θ - θ_prev`` (``= θ̇ Δt``). Per step::

    min_Δ  w ||J_v Δ - (r_d - r(θ_prev))||²  +  h2 ∇(1/μ)(θ_prev)ᵀ Δ  +  (ρ/2) ||Δ||²
    s.t.   lower - θ_prev <= Δ <= upper - θ_prev          (eq. (11): joint and velocity limits)
           δ_k Δ <= (Y V_k - V0_k) Δt                      (eq. (9), the same rows as ESM)

* Tracking: the linearized position error with a large weight ``w`` (1e6). The squared
  norm is the QP counterpart of ESM's ``h1 ||e||``; with ``w`` large it pins the end
  effector as ESM does for ``h1 >= 3 h2`` (see :class:`drake_mh.reactive.esm.ESMConfig`), the
  residual bias being ``h2 ||∇_r(1/μ*)|| / (2 w)`` (about 1e-6 m at the paper's target).
* Manipulability: ``1/μ`` enters by its gradient (a linear term, central differences of the
  batched manipulability, step 1e-6 rad); the proximal term ``(ρ/2)||Δ||²`` makes the
  null-space motion a gradient step of length ``h2/ρ`` (trust-region-like), ``ρ = 40``.
* Constraints: the box of eq. (11) and the obstacle rows built by
  :func:`drake_mh.reactive.esm.problem.build_step`, identical to the metaheuristics'.

The program is built once and updated in place (``UpdateCoefficients``, ``set_bounds``);
it is rebuilt only when a step has more obstacle rows than allocated. OSQP's answer
(tolerance 1e-9; polishing off: it prints to stdout) is finally passed through the same repair as the
metaheuristics' candidates, so tolerance-level violations are removed; the answer is then
checked (``StepSolution.feasible``) like every solver's.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.reactive.esm.problem import ESMObjective, ESMStep
from drake_mh.reactive.esm.solvers import StepSolution, StepSolver


def inverse_manipulability_gradient(robot, theta, h: float = 1e-6) -> np.ndarray:
    """``∇(1/μ)(θ)`` ``(nq,)`` by central differences of ``robot.batch.manipulability``."""
    n = robot.nq
    E = np.eye(n) * h
    mu = robot.batch.manipulability(np.vstack([theta + E, theta - E]))
    inv = 1.0 / np.maximum(mu, 1e-300)
    return (inv[:n] - inv[n:]) / (2.0 * h)


class QPBaseline(StepSolver):
    """Velocity-level QP (OSQP via pydrake ``MathematicalProgram``), same constraints as ESM.

    Args:
        tracking_weight: ``w`` of the tracking term [1/m²].
        damping: ``ρ`` of the proximal term [1/rad²].
        eps: OSQP's absolute and relative tolerances.
    """

    name = "qp"

    def __init__(self, tracking_weight: float = 1e6, damping: float = 40.0, eps: float = 1e-9):
        self.tracking_weight = float(tracking_weight)
        self.damping = float(damping)
        self.eps = float(eps)
        self._prog = None
        self._capacity = -1
        self.reset(None)

    @property
    def budget_label(self) -> str:
        return "OSQP"

    def _build(self, nq: int, rows: int) -> None:
        from pydrake.solvers import MathematicalProgram, OsqpSolver, SolverOptions

        prog = MathematicalProgram()
        x = prog.NewContinuousVariables(nq, "dtheta")
        self._cost = prog.AddQuadraticCost(np.eye(nq), np.zeros(nq), x, is_convex=True)
        self._box = prog.AddBoundingBoxConstraint(-np.ones(nq), np.ones(nq), x)
        self._rows = None
        if rows:
            self._rows = prog.AddLinearConstraint(np.zeros((rows, nq)), np.full(rows, -np.inf),
                                                  np.full(rows, np.inf), x)
        self._solver = OsqpSolver()
        self._options = SolverOptions()
        sid = self._solver.id()
        for name, value in (("eps_abs", self.eps), ("eps_rel", self.eps), ("polishing", 0), ("verbose", 0),
                            ("max_iter", 20000)):
            self._options.SetOption(sid, name, value)
        self._prog, self._x, self._capacity = prog, x, rows

    def solve(self, robot, step: ESMStep) -> StepSolution:
        t0 = time.perf_counter()
        nq = robot.nq
        K = len(step.c)
        if self._prog is None or K > self._capacity or self._x.size != nq:
            self._build(nq, max(K, 8))
        theta_prev = step.theta_prev
        T, J = robot.batch.fk_jacobian(theta_prev[None])
        Jv = J[0, 3:]
        err = step.r_d - T[0, :3, 3]
        w, cfg = self.tracking_weight, step.config
        H = 2.0 * w * Jv.T @ Jv + self.damping * np.eye(nq)
        g = -2.0 * w * Jv.T @ err
        if cfg.h2 > 0:
            g = g + cfg.h2 * inverse_manipulability_gradient(robot, theta_prev)
        self._cost.evaluator().UpdateCoefficients(H, g, is_convex=True)
        self._box.evaluator().set_bounds(step.lower - theta_prev, step.upper - theta_prev)
        if self._rows is not None:
            A = np.zeros((self._capacity, nq))
            ub = np.full(self._capacity, np.inf)
            if K:
                A[:K] = step.A
                ub[:K] = step.c - step.A @ theta_prev
            self._rows.evaluator().UpdateCoefficients(A, np.full(self._capacity, -np.inf), ub)
        result = self._solver.Solve(self._prog, None, self._options)
        message = result.get_solution_result().name
        objective = ESMObjective(robot, step, "repair")
        if result.is_success():
            candidate = theta_prev + np.asarray(result.GetSolution(self._x))
        else:
            candidate = theta_prev
        theta, ok = step.repair(candidate[None])
        theta = theta[0]
        F = float(objective.values(theta[None])[0][0])
        return StepSolution(theta, F, bool(ok[0]), 1, time.perf_counter() - t0, message)
