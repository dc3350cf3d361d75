"""Numba kernels behind :class:`drake_mh.kinematics.BatchKinematics`.

Layout: configurations are processed in blocks of ``BLOCK`` with the block index innermost
(structure of arrays), so that LLVM vectorizes every per-joint operation across
configurations (SIMD). Branches depend on the joint only (kind, signed-permutation flag),
never on the configuration.

``sin``/``cos`` are evaluated by :func:`_sincos_block`, a branch-free vectorizable version of
the classic fdlibm scheme: Cody-Waite reduction by π/2 in three parts and the fdlibm minimax
polynomials on [-π/4, π/4] (coefficients from fdlibm's ``__kernel_sin``/``__kernel_cos``);
absolute error about 1e-16 for |x| <= 1e5 rad. Larger angles (never a joint angle in practice)
are recomputed with ``np.sin``/``np.cos``.
"""

from __future__ import annotations

import numba
import numpy as np

BLOCK = 64

# fdlibm constants: π/2 split for Cody-Waite reduction, and minimax coefficients.
_INV_PIO2 = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
_LARGE = 1e5

# no reassociation: it would break the Cody-Waite reduction; contraction (FMA) is fine
_FASTMATH = {"nnan", "ninf", "nsz", "contract"}


@numba.njit(cache=True, fastmath=_FASTMATH, inline="always")
def _sincos_block(x, s_out, c_out, m):
    """s_out[:m], c_out[:m] = sin(x[:m]), cos(x[:m]) (vectorizable, see module docstring)."""
    large = False
    for b in range(m):
        xb = x[b]
        nf = np.floor(xb * _INV_PIO2 + 0.5)
        r = ((xb - nf * _PIO2_1) - nf * _PIO2_2) - nf * _PIO2_3
        z = r * r
        sp = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        cp = 1.0 - 0.5 * z + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
        n = np.int64(nf)
        odd = (n & 1) == 1
        s = cp if odd else sp
        c = sp if odd else cp
        s_out[b] = -s if (n & 2) == 2 else s
        c_out[b] = -c if ((n + 1) & 2) == 2 else c
        large |= abs(xb) > _LARGE
    if large:
        for b in range(m):
            if abs(x[b]) > _LARGE:
                s_out[b] = np.sin(x[b])
                c_out[b] = np.cos(x[b])


@numba.njit(cache=True, fastmath=_FASTMATH, inline="always")
def frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs):
    """World poses of every moving frame for configurations n0 .. n0+m-1: the forward kinematics
    that the other packages' compiled kernels (the scene's collision checks) build on.

    Args:
        QT: ``(nq, N)`` configurations, coordinate first [rad or m].
        n0, m: the first configuration and how many (``m <= BLOCK``).
        parent, KR, Kp, perm, kind, qidx: the compiled chain as
            :class:`~drake_mh.kinematics.BatchKinematics` passes it (``(F,)`` parents, ``(F, 3, 3)``
            and ``(F, 3)`` fixed rotations and offsets, ``(F,)`` signed-permutation flags, joint
            kinds and coordinate indices).
        R, p: outputs, ``R_WF (F, 3, 3, BLOCK)`` and ``p_WF (F, 3, BLOCK)`` [m], block index
            innermost (lane ``b`` is configuration ``n0 + b``).
        sn, cs: ``(BLOCK,)`` scratch.

    A revolute frame whose
    fixed rotation is a signed permutation (``perm``) takes its parent's columns and the joint's
    rotation in one pass (3-4 ns less per Panda configuration than copying the columns first;
    the same operations, so the same bits).
    """
    for k in range(parent.shape[0]):
        a = parent[k]
        row = QT[qidx[k]]
        revolute = kind[k] == 0
        if revolute:
            _sincos_block(row[n0:n0 + m], sn, cs, m)
        if a >= 0:
            k0, k1, k2 = Kp[k, 0], Kp[k, 1], Kp[k, 2]
            for i in range(3):
                for b in range(m):
                    p[k, i, b] = p[a, i, b] + R[a, i, 0, b] * k0 + R[a, i, 1, b] * k1 + R[a, i, 2, b] * k2
        if a >= 0 and revolute and perm[k, 0] >= 0:
            s0, s1, s2 = perm[k, 0], perm[k, 1], perm[k, 2]
            g0, g1, g2 = KR[k, s0, 0], KR[k, s1, 1], KR[k, s2, 2]
            for i in range(3):
                for b in range(m):
                    r0 = g0 * R[a, i, s0, b]
                    r1 = g1 * R[a, i, s1, b]
                    R[k, i, 2, b] = g2 * R[a, i, s2, b]
                    R[k, i, 0, b] = r0 * cs[b] + r1 * sn[b]
                    R[k, i, 1, b] = r1 * cs[b] - r0 * sn[b]
            continue
        if a < 0:
            for i in range(3):
                for b in range(m):
                    p[k, i, b] = Kp[k, i]
                for j in range(3):
                    for b in range(m):
                        R[k, i, j, b] = KR[k, i, j]
        elif perm[k, 0] >= 0:
            for j in range(3):
                src = perm[k, j]
                sg = KR[k, src, j]
                for i in range(3):
                    for b in range(m):
                        R[k, i, j, b] = sg * R[a, i, src, b]
        else:
            for i in range(3):
                for j in range(3):
                    k0, k1, k2 = KR[k, 0, j], KR[k, 1, j], KR[k, 2, j]
                    for b in range(m):
                        R[k, i, j, b] = R[a, i, 0, b] * k0 + R[a, i, 1, b] * k1 + R[a, i, 2, b] * k2
        if revolute:
            for i in range(3):
                for b in range(m):
                    r0 = R[k, i, 0, b]
                    r1 = R[k, i, 1, b]
                    R[k, i, 0, b] = r0 * cs[b] + r1 * sn[b]
                    R[k, i, 1, b] = r1 * cs[b] - r0 * sn[b]
        else:
            for i in range(3):
                for b in range(m):
                    p[k, i, b] += R[k, i, 2, b] * row[n0 + b]


@numba.njit(cache=True, fastmath=_FASTMATH, inline="always")
def _attached_block(m, a, ER, Ep, R, p, Re, pe):
    """Pose (Re (3,3,B), pe (3,B)) of a frame fixed at offset (ER, Ep) in moving frame a."""
    for i in range(3):
        if a < 0:
            for b in range(m):
                pe[i, b] = Ep[i]
            for j in range(3):
                for b in range(m):
                    Re[i, j, b] = ER[i, j]
        else:
            e0, e1, e2 = Ep[0], Ep[1], Ep[2]
            for b in range(m):
                pe[i, b] = p[a, i, b] + R[a, i, 0, b] * e0 + R[a, i, 1, b] * e1 + R[a, i, 2, b] * e2
            for j in range(3):
                k0, k1, k2 = ER[0, j], ER[1, j], ER[2, j]
                for b in range(m):
                    Re[i, j, b] = R[a, i, 0, b] * k0 + R[a, i, 1, b] * k1 + R[a, i, 2, b] * k2


@numba.njit(cache=True, fastmath=_FASTMATH)
def fk_jacobian(QT, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, T_out, J_out):
    """Poses (N, 4, 4) of a frame and, if want_jac, its geometric Jacobians (N, 6, nq).

    QT is the transposed batch (nq, N). The frame is fixed at (ER, Ep) in moving frame
    ``anchor``; ``on_path[k]`` marks the joints between the world and that frame.
    """
    F = parent.shape[0]
    N = QT.shape[1]
    R = np.empty((F, 3, 3, BLOCK))
    p = np.empty((F, 3, BLOCK))
    sn = np.empty(BLOCK)
    cs = np.empty(BLOCK)
    Re = np.empty((3, 3, BLOCK))
    pe = np.empty((3, BLOCK))
    for n0 in range(0, N, BLOCK):
        m = min(BLOCK, N - n0)
        frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
        _attached_block(m, anchor, ER, Ep, R, p, Re, pe)
        for b in range(m):
            n = n0 + b
            for i in range(3):
                for j in range(3):
                    T_out[n, i, j] = Re[i, j, b]
                T_out[n, i, 3] = pe[i, b]
                T_out[n, 3, i] = 0.0
            T_out[n, 3, 3] = 1.0
        if want_jac:
            for k in range(F):
                col = qidx[k]
                for b in range(m):
                    n = n0 + b
                    if not on_path[k]:
                        for i in range(6):
                            J_out[n, i, col] = 0.0
                    elif kind[k] == 0:
                        zx, zy, zz = R[k, 0, 2, b], R[k, 1, 2, b], R[k, 2, 2, b]
                        dx = pe[0, b] - p[k, 0, b]
                        dy = pe[1, b] - p[k, 1, b]
                        dz = pe[2, b] - p[k, 2, b]
                        J_out[n, 0, col] = zx
                        J_out[n, 1, col] = zy
                        J_out[n, 2, col] = zz
                        J_out[n, 3, col] = zy * dz - zz * dy
                        J_out[n, 4, col] = zz * dx - zx * dz
                        J_out[n, 5, col] = zx * dy - zy * dx
                    else:
                        J_out[n, 0, col] = 0.0
                        J_out[n, 1, col] = 0.0
                        J_out[n, 2, col] = 0.0
                        J_out[n, 3, col] = R[k, 0, 2, b]
                        J_out[n, 4, col] = R[k, 1, 2, b]
                        J_out[n, 5, col] = R[k, 2, 2, b]


@numba.njit(cache=True, fastmath=_FASTMATH)
def points(QT, parent, KR, Kp, perm, kind, qidx, point_anchor, point_offset, out):
    """World positions out (N, S, 3) of points fixed in moving frames (offsets (S, 3))."""
    F = parent.shape[0]
    N = QT.shape[1]
    R = np.empty((F, 3, 3, BLOCK))
    p = np.empty((F, 3, BLOCK))
    sn = np.empty(BLOCK)
    cs = np.empty(BLOCK)
    for n0 in range(0, N, BLOCK):
        m = min(BLOCK, N - n0)
        frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
        for s in range(point_anchor.shape[0]):
            a = point_anchor[s]
            o0, o1, o2 = point_offset[s, 0], point_offset[s, 1], point_offset[s, 2]
            for i in range(3):
                for b in range(m):
                    if a < 0:
                        out[n0 + b, s, i] = point_offset[s, i]
                    else:
                        out[n0 + b, s, i] = (p[a, i, b] + R[a, i, 0, b] * o0 + R[a, i, 1, b] * o1
                                             + R[a, i, 2, b] * o2)


@numba.njit(cache=True, fastmath=_FASTMATH)
def moving_frames(QT, parent, KR, Kp, perm, kind, qidx, R_out, p_out):
    """World rotations R_out (N, F, 3, 3) and origins p_out (N, F, 3) of every moving frame."""
    F = parent.shape[0]
    N = QT.shape[1]
    R = np.empty((F, 3, 3, BLOCK))
    p = np.empty((F, 3, BLOCK))
    sn = np.empty(BLOCK)
    cs = np.empty(BLOCK)
    for n0 in range(0, N, BLOCK):
        m = min(BLOCK, N - n0)
        frames_block(QT, n0, m, parent, KR, Kp, perm, kind, qidx, R, p, sn, cs)
        for k in range(F):
            for b in range(m):
                for i in range(3):
                    p_out[n0 + b, k, i] = p[k, i, b]
                    for j in range(3):
                        R_out[n0 + b, k, i, j] = R[k, i, j, b]


@numba.njit(cache=True, inline="always")
def fk_jacobian_one(q, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, R, p, T, J):
    """Pose ``T (4, 4)`` and geometric Jacobian ``J (6, nq)`` (rows ``[ω; v]``) of one configuration.

    The same compiled chain and recursion as the batched kernel
    (:func:`drake_mh.kinematics.kernels.fk_jacobian`, see :mod:`drake_mh.kinematics`) for a single
    ``q (nq,)``, with scalar ``sin``/``cos`` and no allocation: ``R (F, 3, 3)`` and ``p (F, 3)``
    are work arrays (the world pose of every moving frame); ``J`` is left alone unless
    ``want_jac``. Measured 0.2 µs on the Panda, a quarter of the block kernel's cost at N = 1
    (which is what an LM iteration of one candidate needs). Tested against Drake.
    """
    F = parent.shape[0]
    for k in range(F):
        a = parent[k]
        if a < 0:
            for i in range(3):
                p[k, i] = Kp[k, i]
                for j in range(3):
                    R[k, i, j] = KR[k, i, j]
        else:
            for i in range(3):
                p[k, i] = p[a, i] + R[a, i, 0] * Kp[k, 0] + R[a, i, 1] * Kp[k, 1] + R[a, i, 2] * Kp[k, 2]
            if perm[k, 0] >= 0:
                for j in range(3):
                    src = perm[k, j]
                    sg = KR[k, src, j]
                    for i in range(3):
                        R[k, i, j] = sg * R[a, i, src]
            else:
                for i in range(3):
                    for j in range(3):
                        R[k, i, j] = R[a, i, 0] * KR[k, 0, j] + R[a, i, 1] * KR[k, 1, j] + R[a, i, 2] * KR[k, 2, j]
        x = q[qidx[k]]
        if kind[k] == 0:
            sn = np.sin(x)
            cs = np.cos(x)
            for i in range(3):
                r0 = R[k, i, 0]
                r1 = R[k, i, 1]
                R[k, i, 0] = r0 * cs + r1 * sn
                R[k, i, 1] = r1 * cs - r0 * sn
        else:
            for i in range(3):
                p[k, i] += R[k, i, 2] * x
    for i in range(3):
        if anchor < 0:
            T[i, 3] = Ep[i]
            for j in range(3):
                T[i, j] = ER[i, j]
        else:
            T[i, 3] = p[anchor, i] + R[anchor, i, 0] * Ep[0] + R[anchor, i, 1] * Ep[1] + R[anchor, i, 2] * Ep[2]
            for j in range(3):
                T[i, j] = R[anchor, i, 0] * ER[0, j] + R[anchor, i, 1] * ER[1, j] + R[anchor, i, 2] * ER[2, j]
        T[3, i] = 0.0
    T[3, 3] = 1.0
    if not want_jac:
        return
    for k in range(F):
        col = qidx[k]
        if not on_path[k]:
            for i in range(6):
                J[i, col] = 0.0
        elif kind[k] == 0:
            zx, zy, zz = R[k, 0, 2], R[k, 1, 2], R[k, 2, 2]
            dx = T[0, 3] - p[k, 0]
            dy = T[1, 3] - p[k, 1]
            dz = T[2, 3] - p[k, 2]
            J[0, col] = zx
            J[1, col] = zy
            J[2, col] = zz
            J[3, col] = zy * dz - zz * dy
            J[4, col] = zz * dx - zx * dz
            J[5, col] = zx * dy - zy * dx
        else:
            J[0, col] = 0.0
            J[1, col] = 0.0
            J[2, col] = 0.0
            J[3, col] = R[k, 0, 2]
            J[4, col] = R[k, 1, 2]
            J[5, col] = R[k, 2, 2]


@numba.njit(cache=True)
def fk_one(q, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, R, p, T, J):
    """:func:`fk_jacobian_one` behind ``Robot.fk`` / ``Robot.jacobian``: returns ``False``
    (and computes nothing) when ``q`` holds NaN or inf, so the caller's validation runs in
    the kernel's call (one dispatch, ~1 µs from Python)."""
    for i in range(q.shape[0]):
        if not np.isfinite(q[i]):
            return False
    fk_jacobian_one(q, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, R, p, T, J)
    return True
