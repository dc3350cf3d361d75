"""Batched damped least-squares / Levenberg–Marquardt steps for K IK candidates at once.

The Jacobian baselines (:mod:`drake_mh.ik.jacobian`) and the local phase of the hybrid
(:mod:`drake_mh.ik.hybrid`) share this machinery. One iteration is two calls: the batched
kernel ``Robot.batch.fk_jacobian(Q (K, nq))`` and :func:`lm_step` (numba), which for every
candidate k

1. computes the task error ``e = [w_o ω; Δp]`` with ``Δp = p_WT - p_WE`` [m] and ``ω`` the
   rotation vector of ``R_WT R_WEᵀ`` [rad] (rows ordered as Drake's Jacobian ``[ω; v]``;
   only the 3 translational rows for a position-only target);
2. *adaptive* mode (Levenberg 1944, Marquardt 1963): accepts the trial point if it lowers
   ``|e|²`` (then ``λ ← max(λ·down, λ_min)``), else keeps the previous point and raises
   ``λ ← λ·up``; *plain* mode (the classic pseudo-inverse / DLS iterations) always accepts;
3. tests convergence of the accepted point (``|Δp| <= tol_p``, ``θ <= tol_o``) and
   stagnation (``max_iter`` iterations, ``λ > λ_max``, or ``stall_iters`` iterations in a
   row with less than 10 % decrease of ``|e|²``);
4. takes the damped least-squares step (Wampler 1986; Nakamura & Hanafusa 1986)
   ``Δq = Jᵀ (J Jᵀ + λ I)⁻¹ e`` — the minimum-norm Gauss–Newton step for ``λ → 0`` (the
   pseudo-inverse ``J⁺ e`` when J has full row rank) — plus, with a reference configuration,
   the secondary task ``α (I - Jᵀ (J Jᵀ + λ I)⁻¹ J)(q_ref - q)`` projected (approximately, for
   ``λ > 0``) into the null space of the task, so it does not pull the end effector off the
   target; then projects the new point onto the joint limits (clamping).

The ``m x m`` systems (m = 6 or 3) are solved by an unrolled Cholesky factorization per
candidate inside the kernel: no Python loop over candidates and no per-iteration numpy calls
beyond the FK/Jacobian kernel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["LMSettings", "BatchLM", "lm_step", "CONVERGED", "STALLED", "RUNNING"]

RUNNING, CONVERGED, STALLED = 0, 1, 2


@dataclass(frozen=True)
class LMSettings:
    """Parameters of the batched least-squares iteration.

    Attributes:
        adaptive: Levenberg–Marquardt acceptance with adaptive damping (``True``) or plain
            iterations that always take the step (``False``: classic pseudo-inverse / DLS).
        lam0: initial damping λ [m²] (for plain mode: the fixed damping; ``1e-12`` gives the
            pseudo-inverse of a full-rank J).
        lam_up, lam_down: factors applied to λ after a rejected / accepted step.
        lam_min, lam_max: bounds of λ; beyond ``lam_max`` the candidate counts as stalled.
        max_iter: iterations per start before the candidate counts as stalled.
        stall_iters: consecutive iterations with less than 10 % decrease of ``|e|²`` before
            the candidate counts as stalled.
        ref_gain: α of the null-space pull towards ``q_ref`` (0 disables it).
        tol_factor: fraction of the problem's tolerances the solver aims for, so that Drake's
            verification (which agrees with the batched kernel to ~1e-15) passes with margin.
    """

    adaptive: bool = True
    lam0: float = 1e-3
    lam_up: float = 8.0
    lam_down: float = 0.2
    lam_min: float = 1e-12
    lam_max: float = 1e4
    max_iter: int = 40
    stall_iters: int = 8
    ref_gain: float = 0.0
    tol_factor: float = 0.5


@numba.njit(cache=True)
def _pose_error(T, p_t, R_t, has_rot, e):
    """``e (6,) = [ω; Δp]`` for one pose ``T (4, 4)`` (ω: rotation vector of R_t Rᵀ)."""
    e[3] = p_t[0] - T[0, 3]
    e[4] = p_t[1] - T[1, 3]
    e[5] = p_t[2] - T[2, 3]
    if not has_rot:
        e[0] = 0.0
        e[1] = 0.0
        e[2] = 0.0
        return
    E = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            E[i, j] = R_t[i, 0] * T[j, 0] + R_t[i, 1] * T[j, 1] + R_t[i, 2] * T[j, 2]
    wx = 0.5 * (E[2, 1] - E[1, 2])
    wy = 0.5 * (E[0, 2] - E[2, 0])
    wz = 0.5 * (E[1, 0] - E[0, 1])
    s = np.sqrt(wx * wx + wy * wy + wz * wz)
    c = 0.5 * (E[0, 0] + E[1, 1] + E[2, 2] - 1.0)
    theta = np.arctan2(s, c)
    if s > 1e-9:
        scale = theta / s
        e[0], e[1], e[2] = scale * wx, scale * wy, scale * wz
    elif c > 0.0:  # θ ~ s: the skew part is the rotation vector to second order
        e[0], e[1], e[2] = wx, wy, wz
    else:  # θ ~ π: axis from the largest column of (E + I) / 2 = a aᵀ
        i = 0
        for j in range(1, 3):
            if E[j, j] > E[i, i]:
                i = j
        d = np.sqrt(max(0.5 * (E[i, i] + 1.0), 1e-300))
        for j in range(3):
            e[j] = np.pi * 0.5 * (E[j, i] + (1.0 if j == i else 0.0)) / d


@numba.njit(cache=True)
def lm_step(T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status,
            p_t, R_t, has_rot, w_o, lower, upper,
            adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters,
            ref_gain, q_ref, tol_p2, tol_o2, Qn):
    """One iteration for every candidate (see the module docstring).

    Args:
        T, J: ``(K, 4, 4)``, ``(K, 6, nq)`` FK and Jacobians at the trial points ``Qt (K, nq)``.
        Qa, Ea, Ja, fa: accepted points ``(K, nq)``, their unweighted errors ``[ω; Δp]``
            ``(K, 6)``, Jacobians ``(K, 6, nq)`` and weighted ``|e_w|²`` ``(K,)`` (updated in
            place).
        lam, stall, iters, fresh: per-candidate damping, stagnation counter, iteration count,
            and whether the trial point is a new start (updated in place).
        status: ``(K,)`` out: RUNNING, CONVERGED or STALLED.
        tol_p2, tol_o2: squared tolerances [m², rad²] (orientation unweighted).
        Qn: ``(K, nq)`` out: the next trial points.

    Returns:
        Index of the converged candidate with the smallest error, or -1.
    """
    K, nq = Qt.shape
    r0 = 0 if has_rot else 3
    m = 6 - r0
    e = np.empty(6)
    A = np.empty((m, m))
    L = np.empty((m, m))
    y = np.empty(m)
    z = np.empty(m)
    r = np.empty(nq)
    best, best_f = -1, np.inf
    for k in range(K):
        for j in range(nq):  # default next trial: stay (rows that stop are restarted by the caller)
            Qn[k, j] = Qt[k, j]
        _pose_error(T[k], p_t, R_t, has_rot, e)
        f = 0.0
        for i in range(r0, 6):
            f += (w_o * w_o if i < 3 else 1.0) * e[i] * e[i]
        if not np.isfinite(f):
            status[k] = STALLED
            continue
        if fresh[k] or (not adaptive) or f < fa[k]:
            if not fresh[k] and f > 0.9 * fa[k]:
                stall[k] += 1
            else:
                stall[k] = 0
            if adaptive and not fresh[k]:
                lam[k] = max(lam[k] * lam_down, lam_min)
            for j in range(nq):
                Qa[k, j] = Qt[k, j]
            for i in range(6):
                Ea[k, i] = e[i]
                for j in range(nq):
                    Ja[k, i, j] = J[k, i, j]
            fa[k] = f
            fresh[k] = False
        else:
            lam[k] *= lam_up
            stall[k] += 1
        iters[k] += 1
        ep2 = Ea[k, 3] ** 2 + Ea[k, 4] ** 2 + Ea[k, 5] ** 2
        eo2 = Ea[k, 0] ** 2 + Ea[k, 1] ** 2 + Ea[k, 2] ** 2
        if ep2 <= tol_p2 and eo2 <= tol_o2:
            status[k] = CONVERGED
            if fa[k] < best_f:
                best, best_f = k, fa[k]
            continue
        if iters[k] >= max_iter or lam[k] > lam_max or stall[k] >= stall_iters:
            status[k] = STALLED
            continue
        status[k] = RUNNING
        # A = Jw Jwᵀ + λ I over the task rows (rotational rows weighted by w_o)
        for a in range(m):
            wa = w_o if a + r0 < 3 else 1.0
            for b in range(a + 1):
                wb = w_o if b + r0 < 3 else 1.0
                s = 0.0
                for j in range(nq):
                    s += Ja[k, a + r0, j] * Ja[k, b + r0, j]
                A[a, b] = wa * wb * s
            A[a, a] += lam[k]
        ok = True
        for a in range(m):  # Cholesky A = L Lᵀ
            for b in range(a + 1):
                s = A[a, b]
                for c in range(b):
                    s -= L[a, c] * L[b, c]
                if a == b:
                    if s <= 1e-300:
                        ok = False
                        break
                    L[a, a] = np.sqrt(s)
                else:
                    L[a, b] = s / L[b, b]
            if not ok:
                break
        if not ok:
            status[k] = STALLED
            continue
        for a in range(m):  # rhs y = e_w
            y[a] = (w_o if a + r0 < 3 else 1.0) * Ea[k, a + r0]
        if ref_gain > 0.0:
            for j in range(nq):
                r[j] = ref_gain * (q_ref[j] - Qa[k, j])
            for a in range(m):
                wa = w_o if a + r0 < 3 else 1.0
                s = 0.0
                for j in range(nq):
                    s += Ja[k, a + r0, j] * r[j]
                z[a] = wa * s
        # solve L Lᵀ y = y (and z)
        for a in range(m):
            s = y[a]
            t = z[a] if ref_gain > 0.0 else 0.0
            for c in range(a):
                s -= L[a, c] * y[c]
                t -= L[a, c] * z[c]
            y[a] = s / L[a, a]
            z[a] = t / L[a, a]
        for a in range(m - 1, -1, -1):
            s = y[a]
            t = z[a]
            for c in range(a + 1, m):
                s -= L[c, a] * y[c]
                t -= L[c, a] * z[c]
            y[a] = s / L[a, a]
            z[a] = t / L[a, a]
        for j in range(nq):
            dq = 0.0
            for a in range(m):
                wa = w_o if a + r0 < 3 else 1.0
                dq += wa * Ja[k, a + r0, j] * (y[a] - (z[a] if ref_gain > 0.0 else 0.0))
            if ref_gain > 0.0:
                dq += r[j]
            v = Qa[k, j] + dq
            if not np.isfinite(v):
                status[k] = STALLED
                v = Qa[k, j]
            Qn[k, j] = min(max(v, lower[j]), upper[j])
    return best


class BatchLM:
    """State of K least-squares candidates on one :class:`drake_mh.ik.problem.IKProblem`.

    Args:
        problem: the IK problem (target, tolerances, limits, reference configuration).
        K: number of candidates iterated together.
        settings: :class:`LMSettings`.

    Use :meth:`start` to put new starting points into some rows and :meth:`iterate` to run one
    iteration of all of them (``K`` FK + Jacobian evaluations).
    """

    def __init__(self, problem, K: int, settings: LMSettings):
        nq = problem.nq
        self.problem = problem
        self.settings = settings
        self.K = K
        self.Qt = np.empty((K, nq))
        self.Qn = np.empty((K, nq))
        self.Qa = np.empty((K, nq))
        self.Ea = np.zeros((K, 6))
        self.Ja = np.zeros((K, 6, nq))
        self.fa = np.full(K, np.inf)
        self.lam = np.full(K, settings.lam0)
        self.stall = np.zeros(K, dtype=np.int64)
        self.iters = np.zeros(K, dtype=np.int64)
        self.fresh = np.ones(K, dtype=np.bool_)
        self.status = np.zeros(K, dtype=np.int64)
        has_rot = problem.R_WT is not None
        ref = problem.q_ref is not None and settings.ref_gain > 0
        tf = settings.tol_factor
        self._const = (
            np.ascontiguousarray(problem.p_WT), np.ascontiguousarray(problem.R_WT if has_rot else np.eye(3)),
            has_rot, float(problem.orientation_weight) if has_rot else 1.0,
            np.ascontiguousarray(problem.lower), np.ascontiguousarray(problem.upper),
            settings.adaptive, settings.lam_down, settings.lam_up, settings.lam_min, settings.lam_max,
            settings.max_iter, settings.stall_iters, settings.ref_gain if ref else 0.0,
            np.ascontiguousarray(problem.q_ref if ref else np.zeros(nq)),
            (tf * problem.position_tolerance) ** 2, (tf * problem.orientation_tolerance) ** 2,
        )
        self._fk_jacobian = problem.robot.batch.fk_jacobian
        self._frame = problem.frame

    def start(self, rows, Q0) -> None:
        """Restarts candidates ``rows`` from ``Q0 (len(rows), nq)`` (clamped into the limits)."""
        self.Qt[rows] = np.clip(Q0, self.problem.lower, self.problem.upper)
        self.fresh[rows] = True
        self.iters[rows] = 0
        self.stall[rows] = 0
        self.lam[rows] = self.settings.lam0
        self.fa[rows] = np.inf

    def iterate(self) -> int:
        """One iteration of every candidate; returns a converged row or -1 (see :func:`lm_step`)."""
        T, J = self._fk_jacobian(self.Qt, self._frame)
        best = lm_step(T, J, self.Qt, self.Qa, self.Ea, self.Ja, self.fa, self.lam, self.stall, self.iters,
                       self.fresh, self.status, *self._const, self.Qn)
        self.Qt, self.Qn = self.Qn, self.Qt
        return int(best)

    def best_row(self) -> int:
        """Row of the accepted point with the smallest error."""
        return int(np.argmin(self.fa))
