"""Numba kernels of the ESM control step: objective values, feasibility test and repair.

All kernels loop over the rows of a population ``X (P, nq)`` in compiled code, so the
per-generation cost of the ESM objective is one call of ``Robot.batch.fk_jacobian`` plus
one of these kernels (no Python loop over agents, no ``numpy.linalg`` call on ``(P, 3, 3)``
stacks, whose per-call overhead dominates at the population sizes used here).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def esm_values(T, J, r_d, h1, h2, F_out, e_out, mu_out):
    """ESM objective (eq. (10)) from poses and Jacobians of the end effector.

    Args:
        T: ``(P, 4, 4)`` poses ``X_WE``.
        J: ``(P, 6, nq)`` Jacobians, rows ``[ω; v]`` (translational rows 3..5 are used).
        r_d: ``(3,)`` target position ``p_WE_desired`` [m].
        h1, h2: weights of eq. (10).
        F_out, e_out, mu_out: ``(P,)`` outputs: ``h1 e + h2 / μ``, tracking error ``e`` [m],
            translational manipulability ``μ = sqrt(det(J_v J_vᵀ))`` (eq. (3)).
    """
    P = T.shape[0]
    nq = J.shape[2]
    for i in range(P):
        ex = T[i, 0, 3] - r_d[0]
        ey = T[i, 1, 3] - r_d[1]
        ez = T[i, 2, 3] - r_d[2]
        e = np.sqrt(ex * ex + ey * ey + ez * ez)
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        for k in range(nq):
            a = J[i, 3, k]
            b = J[i, 4, k]
            c = J[i, 5, k]
            m00 += a * a
            m01 += a * b
            m02 += a * c
            m11 += b * b
            m12 += b * c
            m22 += c * c
        det = m00 * (m11 * m22 - m12 * m12) - m01 * (m01 * m22 - m12 * m02) + m02 * (m01 * m12 - m11 * m02)
        mu = np.sqrt(det) if det > 0.0 else 0.0
        e_out[i] = e
        mu_out[i] = mu
        if h2 == 0.0:
            F_out[i] = h1 * e
        elif mu > 0.0:
            F_out[i] = h1 * e + h2 / mu
        else:
            F_out[i] = np.inf


@numba.njit(cache=True, inline="always")
def _satisfies_rows(X, i, A, c, tol):
    """Whether row ``i`` of ``X`` satisfies ``A x <= c + tol`` (sums over the joints in order)."""
    n = X.shape[1]
    for k in range(A.shape[0]):
        s = 0.0
        for j in range(n):
            s += A[k, j] * X[i, j]
        if s > c[k] + tol:
            return False
    return True


@numba.njit(cache=True)
def feasible(X, A, c, lower, upper, tol, out):
    """``out[i]``: row i of ``X`` lies in the box and satisfies ``A x <= c + tol``."""
    P, n = X.shape
    for i in range(P):
        ok = True
        for j in range(n):
            if X[i, j] < lower[j] or X[i, j] > upper[j]:
                ok = False
                break
        out[i] = ok and _satisfies_rows(X, i, A, c, tol)


@numba.njit(cache=True)
def repair(X, A, c, lower, upper, sweeps, tol, out):
    """Moves every row of ``X`` into ``{lower <= x <= upper, A x <= c}`` (in place).

    Cyclic projection (POCS): per sweep, each violated half-space ``a_k x <= c_k`` is
    projected onto (aimed at ``c_k - tol / 2`` so rounding keeps the point inside), then the
    box is enforced by clipping; a row that needs no change is left untouched. ``out[i]``
    reports whether row i is feasible (within ``tol``) after at most ``sweeps`` sweeps.
    """
    P, n = X.shape
    K = A.shape[0]
    norm2 = np.empty(K)
    for k in range(K):
        s = 0.0
        for j in range(n):
            s += A[k, j] * A[k, j]
        norm2[k] = s
    for i in range(P):
        for j in range(n):
            if X[i, j] < lower[j]:
                X[i, j] = lower[j]
            elif X[i, j] > upper[j]:
                X[i, j] = upper[j]
        for _ in range(sweeps):
            changed = False
            for k in range(K):
                s = 0.0
                for j in range(n):
                    s += A[k, j] * X[i, j]
                if s > c[k] and norm2[k] > 0.0:
                    step = (s - c[k] + 0.5 * tol) / norm2[k]
                    for j in range(n):
                        X[i, j] -= step * A[k, j]
                    changed = True
            if not changed:
                break
            for j in range(n):
                if X[i, j] < lower[j]:
                    X[i, j] = lower[j]
                elif X[i, j] > upper[j]:
                    X[i, j] = upper[j]
        out[i] = _satisfies_rows(X, i, A, c, tol)


@numba.njit(cache=True)
def feasible_columns(QT, A, c, lower, upper, tol, out):
    """:func:`feasible` for a transposed batch ``QT (n, P)`` (one configuration per column).

    The same test with the same sums (``A_k x`` accumulated over the joints in order, so the
    verdicts are identical), computed for all ``P`` configurations at once: the loops over
    configurations are innermost and vectorize (SIMD), without :func:`feasible`'s early exit.
    Used by the compiled AMNN step, whose layers are already transposed for the kinematics.
    """
    n, P = QT.shape
    K = A.shape[0]
    s = np.empty(P)
    for i in range(P):
        out[i] = True
    for j in range(n):
        lo, hi = lower[j], upper[j]
        for i in range(P):
            x = QT[j, i]
            if x < lo or x > hi:
                out[i] = False
    for k in range(K):
        for i in range(P):
            s[i] = 0.0
        for j in range(n):
            a = A[k, j]
            for i in range(P):
                s[i] += a * QT[j, i]
        bound = c[k] + tol
        for i in range(P):
            if s[i] > bound:
                out[i] = False
