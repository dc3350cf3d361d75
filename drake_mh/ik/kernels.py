"""Single-configuration kernels of the compiled LM restart loop (:func:`drake_mh.ik.lm.lm_run`).

* :func:`fk_jacobian_one`: FK and geometric Jacobian of one configuration from the compiled
  chain of :class:`drake_mh.kinematics.BatchKinematics`, without allocation;
* :func:`uniform_hash`: the counter-based generator of the restarts' starting points.

Both are inlined into the loop (numba ``inline="always"``).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["fk_jacobian_one", "uniform_hash"]

@numba.njit(cache=True, inline="always")
def fk_jacobian_one(q, parent, KR, Kp, perm, kind, qidx, anchor, ER, Ep, on_path, want_jac, R, p, T, J):
    """Pose ``T (4, 4)`` and geometric Jacobian ``J (6, nq)`` (rows ``[ω; v]``) of one configuration.

    The same compiled chain and recursion as the batched kernel
    (:func:`drake_mh._kernels.fk_jacobian`, see :mod:`drake_mh.kinematics`) for a single
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


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


@numba.njit(cache=True, inline="always")
def uniform_hash(seed, n):
    """A uniform number in [0, 1) from ``(seed, n)``: SplitMix64's output function (Steele,
    Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014) applied to
    ``seed + (n + 1) γ``, i.e. draw ``n`` of the SplitMix64 stream started at ``seed``.

    Counter-based, so a start depends on the seed and its index only (no state to carry
    between compiled calls, no numpy ``Generator`` to build per solve: 7 µs). ``seed`` is a
    ``uint64``, ``n`` an integer >= 0.
    """
    z = seed + (np.uint64(n) + np.uint64(1)) * _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    z = z ^ (z >> np.uint64(31))
    return np.float64(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)
