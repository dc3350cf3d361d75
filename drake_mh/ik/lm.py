"""Batched damped least-squares / Levenberg–Marquardt steps for K IK candidates at once.

The Jacobian baselines (:mod:`drake_mh.ik.jacobian`) and both phases of the hybrid
(:mod:`drake_mh.ik.hybrid`) share this machinery. They run :func:`lm_run` (via
:meth:`BatchLM.run`): iterations *and* restarts inside one compiled call, FK and Jacobian of
each candidate by :func:`drake_mh.kinematics.kernels.fk_jacobian_one`, returning when a candidate
converges or its starts run out. :meth:`BatchLM.iterate` (one iteration per call: the batched
kernel ``Robot.batch.fk_jacobian(Q (K, nq))`` and :func:`lm_step`) remains for step-by-step
use. Per candidate k, an iteration

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
   target (the damping λ, or ``λ |e_w|²`` with ``error_damping``: Chan & Lawrence 1988); then
   projects the new point onto the joint limits (clamping), unless ``project_limits`` is off:
   then iterates may leave the limits and a converged point is accepted only if whole turns
   of its revolute joints bring it within them.

The ``m x m`` systems (m = 6 or 3) are solved by an unrolled Cholesky factorization per
candidate inside the kernel: no Python loop over candidates and no per-iteration numpy calls
beyond the FK/Jacobian kernel.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh._support.random import uniform_at
from drake_mh.kinematics.kernels import fk_jacobian_one

__all__ = ["LMSettings", "BatchLM", "lm_step", "lm_run", "CONVERGED", "STALLED",
           "RUNNING"]

#: row states: iterating, converged (to the solver's tolerances), stalled (to be restarted)
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
        project_limits: clamp every iterate onto the joint limits (``True``); ``False`` lets
            iterates leave them and accepts a converged point only if whole turns of its
            revolute joints bring it within them (else the start counts as stalled), as
            robotics-toolbox's ``ik_LM`` does. Used by :meth:`BatchLM.run` only;
            :meth:`BatchLM.iterate` always projects.
        error_damping: damp with ``λ |e_w|²`` instead of ``λ`` (Chan & Lawrence, "General
            inverse kinematics with the error damped pseudoinverse", ICRA 1988; the default
            of robotics-toolbox's ``ik_LM``, there in joint space): heavy damping far from the
            target, Gauss-Newton steps near it. Used by :meth:`BatchLM.run` only.
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
    project_limits: bool = True
    error_damping: bool = False


@numba.njit(cache=True, inline="always")
def _pose_error(T, p_t, R_t, has_rot, e, E):
    """``e (6,) = [ω; Δp]`` for one pose ``T (4, 4)`` (ω: rotation vector of R_t Rᵀ; E: (3, 3) work)."""
    e[3] = p_t[0] - T[0, 3]
    e[4] = p_t[1] - T[1, 3]
    e[5] = p_t[2] - T[2, 3]
    if not has_rot:
        e[0] = 0.0
        e[1] = 0.0
        e[2] = 0.0
        return
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
    nq = Qt.shape[1]
    return _lm_step(T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status,
                    p_t, R_t, has_rot, w_o, lower, upper,
                    adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters,
                    ref_gain, q_ref, tol_p2, tol_o2, Qn, np.empty(6), np.empty((6, 6)), np.empty((6, 6)),
                    np.empty(6), np.empty(6), np.empty(nq), np.empty((3, 3)))


@numba.njit(cache=True)
def _lm_step(T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status,
             p_t, R_t, has_rot, w_o, lower, upper,
             adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters,
             ref_gain, q_ref, tol_p2, tol_o2, Qn, e, A, L, y, z, r, E):
    """:func:`lm_step` with its work arrays ``e (6,), A, L (6, 6), y, z (6,), r (nq,), E (3, 3)``."""
    best, best_f = -1, np.inf
    for k in range(Qt.shape[0]):
        if _lm_row(k, T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status, Qn,
                   p_t, R_t, has_rot, w_o, lower, upper, ref_gain, q_ref, tol_p2, tol_o2,
                   (adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters, True, False),
                   (e, A, L, y, z, r, E), lower) and fa[k] < best_f:
            best, best_f = k, fa[k]
    return best


@numba.njit(cache=True, inline="always")
def _lm_row(k, T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status, Qn,
            p_t, R_t, has_rot, w_o, lower, upper, ref_gain, q_ref, tol_p2, tol_o2, settings, work, revolute):
    """One iteration of row ``k`` (the loop body of :func:`lm_step`); returns whether it converged.

    ``settings = (adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters, project,
    error_damping)`` and
    ``work = (e, A, L, y, z, r, E)`` are packed in tuples: numba inlines calls of at most 32
    arguments, and an inlined row step saves ~0.25 µs of call overhead per iteration.
    """
    adaptive, lam_down, lam_up, lam_min, lam_max, max_iter, stall_iters, project, error_damping = settings
    e, A, L, y, z, r, E = work
    nq = Qt.shape[1]
    r0 = 0 if has_rot else 3
    m = 6 - r0
    for j in range(nq):  # default next trial: stay (rows that stop are restarted by the caller)
        Qn[k, j] = Qt[k, j]
    _pose_error(T[k], p_t, R_t, has_rot, e, E)
    f = 0.0
    for i in range(r0, 6):
        f += (w_o * w_o if i < 3 else 1.0) * e[i] * e[i]
    if not np.isfinite(f):
        status[k] = STALLED
        return False
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
        if not project and not _into_limits(Qa[k], lower, upper, revolute):
            status[k] = STALLED  # converged outside the limits: a new start
            return False
        status[k] = CONVERGED
        return True
    if iters[k] >= max_iter or lam[k] > lam_max or stall[k] >= stall_iters:
        status[k] = STALLED
        return False
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
        A[a, a] += lam[k] * fa[k] if error_damping else lam[k]
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
        return False
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
        Qn[k, j] = min(max(v, lower[j]), upper[j]) if project else v
    return False


@numba.njit(cache=True, inline="always")
def _into_limits(q, lower, upper, revolute):
    """Moves revolute coordinates of ``q`` outside the limits by whole turns into them, in place.

    Returns whether every coordinate is then within its limits (the pose is unchanged up to
    rounding: sin and cos have period 2π).
    """
    for j in range(q.shape[0]):
        v = q[j]
        if lower[j] <= v <= upper[j]:
            continue
        if not revolute[j]:
            return False
        v = lower[j] + (v - lower[j]) % (2.0 * np.pi)
        if v > upper[j]:
            return False
        q[j] = v
    return True


@numba.njit(cache=True)
def lm_run(starts, n_starts, gen_seed, cursor, max_evals, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status,
           best_q, best_f,
           chain, p_t, R_t, has_rot, w_o, lower, upper, lam0, settings, ref_gain, q_ref, tol_p2, tol_o2, revolute,
           Qn, T, J):
    """Iterates K candidates with restarts inside one compiled call, until one converges.

    Every iteration evaluates FK + Jacobian of the K trial points (:func:`fk_jacobian_one`)
    and takes one LM step per row (the row step of :func:`lm_step`). A row that stalls (or
    that the caller marked ``STALLED``) is restarted from the next start. The call returns as
    soon as a row converges, when a stalled row finds no start left (the caller then brings
    new starts, e.g. a new generation), or before the next iteration could exceed
    ``max_evals`` evaluations; so a Python caller pays one round trip per converged candidate
    or per batch of starts instead of one per iteration. The state carries over from call to
    call.

    Args:
        starts: ``(M, nq)`` given starting points within the limits: starts ``0 .. M-1``.
        n_starts: number of starts; starts ``M .. n_starts-1`` are drawn uniformly within
            the limits by :func:`drake_mh._support.random.uniform_at` with ``gen_seed`` (start c, joint j: draw
            ``c nq + j``), so they depend on the seed and the index only.
        gen_seed: ``uint64`` seed of the generated starts.
        cursor: index of the next unused start.
        max_evals: most configurations (FK + Jacobian of each row's trial point per
            iteration) this call may evaluate.
        Qt ... status: the state of :class:`BatchLM` (see :func:`lm_step`), updated in place.
        best_q, best_f: ``(nq,)`` and ``(1,)``: the accepted point with the smallest weighted
            error, within the limits, of every start abandoned so far (updated in place; the
            answer of a failure).
        chain: ``(parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path)``, the compiled
            chain and frame of ``BatchKinematics``.
        p_t ... upper, ref_gain ... tol_o2: as :func:`lm_step`; ``lam0``: damping of a new
            start; ``settings``: ``(adaptive, lam_down, lam_up, lam_min, lam_max, max_iter,
            stall_iters, project, error_damping)`` (``project``: clamp every step onto the
            limits, else let iterates leave them and accept a converged point only if it is
            within them after whole turns of its revolute joints; ``error_damping``: damping
            ``λ |e_w|²``); ``revolute``: ``(nq,)`` bool.
        Qn, T, J: work arrays ``(K, nq)``, ``(K, 4, 4)``, ``(K, 6, nq)``.

    Returns:
        ``(row, evals, cursor)``: the converged row (smallest error) or -1, the evaluations
        spent, the index of the next unused start.
    """
    parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path = chain
    K, nq = Qt.shape
    M = starts.shape[0]
    F = parent.shape[0]
    Rw = np.empty((F, 3, 3))
    pw = np.empty((F, 3))
    work = (np.empty(6), np.empty((6, 6)), np.empty((6, 6)), np.empty(6), np.empty(6), np.empty(nq), np.empty((3, 3)))
    evals = 0
    while True:
        for k in range(K):  # restart stalled rows from the next start
            if status[k] != STALLED:
                continue
            if fa[k] < best_f[0] and (settings[7] or _into_limits(Qa[k], lower, upper, revolute)):
                best_f[0] = fa[k]  # the best point within the limits (free iterates may be outside)
                for j in range(nq):
                    best_q[j] = Qa[k, j]
                fa[k] = np.inf  # counted once
            if cursor >= n_starts or evals + K > max_evals:
                return -1, evals, cursor  # the caller brings new starts or budget
            if cursor < M:
                for j in range(nq):
                    Qt[k, j] = starts[cursor, j]
            else:  # uniform within the limits, from the counter-based generator
                for j in range(nq):
                    Qt[k, j] = lower[j] + (upper[j] - lower[j]) * uniform_at(gen_seed, cursor * nq + j)
            cursor += 1
            fresh[k] = True
            iters[k] = 0
            stall[k] = 0
            lam[k] = lam0
            fa[k] = np.inf
            status[k] = RUNNING
        if evals + K > max_evals:
            return -1, evals, cursor
        best, best_fk = -1, np.inf
        for k in range(K):
            fk_jacobian_one(Qt[k], parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, True, Rw, pw, T[k], J[k])
            evals += 1
            conv = _lm_row(k, T, J, Qt, Qa, Ea, Ja, fa, lam, stall, iters, fresh, status, Qn,
                           p_t, R_t, has_rot, w_o, lower, upper, ref_gain, q_ref, tol_p2, tol_o2,
                           settings, work, revolute)
            for j in range(nq):
                Qt[k, j] = Qn[k, j]
            if conv and fa[k] < best_fk:
                best, best_fk = k, fa[k]
        if best >= 0:
            return best, evals, cursor


#: per BatchKinematics: {frame: (chain tuple of lm_run, revolute mask)}
_CHAINS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _compiled_chain(batch, frame: str | None) -> tuple[tuple, np.ndarray]:
    """``lm_run``'s chain tuple and the ``(nq,)`` revolute mask of ``batch`` (cached: ~4 µs a solve)."""
    per_frame = _CHAINS.setdefault(batch, {})
    if frame not in per_frame:
        revolute = np.zeros(batch.nq, dtype=np.bool_)
        revolute[batch.chain.qidx[batch.chain.kind == 0]] = True
        per_frame[frame] = (tuple(batch.chain_arrays) + tuple(batch.frame_arrays(frame)), revolute)
    return per_frame[frame]


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
        # np.empty + fill: np.full / np.ones are Python-level wrappers (~1.5 µs each per solve)
        self.fa = np.empty(K)
        self.fa.fill(np.inf)
        self.lam = np.empty(K)
        self.lam.fill(float(settings.lam0))
        self.stall = np.zeros(K, dtype=np.int64)
        self.iters = np.zeros(K, dtype=np.int64)
        self.fresh = np.empty(K, dtype=np.bool_)
        self.fresh.fill(True)
        self.status = np.zeros(K, dtype=np.int64)
        has_rot = problem.R_WT is not None
        ref = problem.q_ref is not None and settings.ref_gain > 0
        tf = settings.tol_factor
        self._const = (
            np.ascontiguousarray(problem.p_WT), np.ascontiguousarray(problem.R_WT if has_rot else np.eye(3)),
            has_rot, float(problem.orientation_weight) if has_rot else 1.0,
            np.ascontiguousarray(problem.lower), np.ascontiguousarray(problem.upper),
            bool(settings.adaptive), float(settings.lam_down), float(settings.lam_up), float(settings.lam_min),
            float(settings.lam_max), int(settings.max_iter), int(settings.stall_iters),
            float(settings.ref_gain) if ref else 0.0,
            np.ascontiguousarray(problem.q_ref if ref else np.zeros(nq)),
            float(tf * problem.position_tolerance) ** 2, float(tf * problem.orientation_tolerance) ** 2,
        )
        self._fk_jacobian = problem.robot.batch.fk_jacobian
        self._frame = problem.frame
        self.best_q = np.zeros(nq)  # see run()
        self.best_f = np.empty(1)
        self.best_f.fill(np.inf)
        self._run_args = None  # built by the first run()

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
        core = compiled_core()
        if core is not None:  # the compiled core: nothing compiles at call time
            best = core.lm_step(T, J, self.Qt, self.Qa, self.Ea, self.Ja, self.fa, self.lam, self.stall, self.iters,
                                self.fresh, self.status, self.Qn, self._const)
        else:
            best = lm_step(T, J, self.Qt, self.Qa, self.Ea, self.Ja, self.fa, self.lam, self.stall, self.iters,
                           self.fresh, self.status, *self._const, self.Qn)
        self.Qt, self.Qn = self.Qn, self.Qt
        return int(best)

    def run(self, starts: np.ndarray, cursor: int, max_evals: int, n_starts: int | None = None,
            gen_seed: int = 0) -> tuple[int, int, int]:
        """Iterates until a row converges, with restarts, in one compiled call (:func:`lm_run`).

        Rows whose status is ``STALLED`` are restarted from the next start: ``starts[cursor]``
        while ``cursor < len(starts)``, then points drawn uniformly within the limits from
        ``gen_seed`` up to ``n_starts`` starts in all. The best accepted point of every
        abandoned start is kept in :attr:`best_q` / :attr:`best_f`.

        Args:
            starts: ``(M, nq)`` C-contiguous starting points within the limits (M may be 0).
            cursor: index of the next unused start.
            max_evals: most configurations to evaluate in this call.
            n_starts: starts in all (default ``len(starts)``: none generated).
            gen_seed: seed of the generated starts (an integer, used modulo 2⁶⁴).

        Returns:
            ``(row, evals, cursor)``: a converged row or -1, evaluations spent, next start.
        """
        if self._run_args is None:
            nq, K = self.problem.nq, self.K
            c = self._const
            self._T = np.empty((K, 4, 4))
            self._J = np.empty((K, 6, nq))
            chain, revolute = _compiled_chain(self.problem.robot.batch, self._frame)
            self._run_args = (chain, *c[:6], float(self.settings.lam0),
                              c[6:13] + (bool(self.settings.project_limits), bool(self.settings.error_damping)),
                              *c[13:], revolute)
        n_starts = len(starts) if n_starts is None else int(n_starts)
        kinematics = self.problem.robot.batch.core_kinematics()
        if kinematics is not None:  # the compiled core: nothing compiles at call time
            chain, revolute = _compiled_chain(self.problem.robot.batch, self._frame)
            anchor, ER, Ep, on_path = chain[6:]
            c = self._const
            row, evals, cursor = compiled_core().lm_run(
                kinematics, anchor, ER.ravel(), Ep, on_path, starts, n_starts, int(gen_seed) % 2**64, int(cursor),
                int(max_evals), self.Qt, self.Qa, self.Ea, self.Ja, self.fa, self.lam, self.stall, self.iters,
                self.fresh, self.status, self.best_q, self.best_f, c, float(self.settings.lam0),
                c[6:13] + (bool(self.settings.project_limits), bool(self.settings.error_damping)), revolute, self.Qn,
                self._T, self._J)
            return int(row), int(evals), int(cursor)
        row, evals, cursor = lm_run(starts, n_starts, np.uint64(int(gen_seed) % 2**64), int(cursor),
                                    int(max_evals), self.Qt, self.Qa, self.Ea, self.Ja, self.fa, self.lam,
                                    self.stall, self.iters, self.fresh, self.status, self.best_q, self.best_f,
                                    *self._run_args, self.Qn, self._T, self._J)
        return int(row), int(evals), int(cursor)

    def best_row(self) -> int:
        """Row of the accepted point with the smallest error."""
        return int(np.argmin(self.fa))
