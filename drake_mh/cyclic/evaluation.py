"""Fused numba kernel: the whole constant-k evaluation of a population in one pass.

Same computation as :meth:`drake_mh.cyclic.problem.ThreeLinkProblem.evaluate` (which keeps the
joint angles for inspection; this kernel keeps none): for every k, over the N samples, the
closed-form IK (eqs. (7)-(12), (19)-(20)), continuous joint angles (unwrapping, then the 2π
window ``[lower, lower + 2π)`` set by the first sample), limit excess, link-obstacle clearance,
closure and the MATLAB-style eq. (1). ``tests/cyclic/test_evaluation.py`` checks it against the
numpy path; it takes about a fifth of the numpy path's time (P = 20, N = 1000).
"""

from __future__ import annotations

import math

import numba
import numpy as np

TWO_PI = 2.0 * math.pi


@numba.njit(cache=True, nogil=True)
def evaluate_population(k, p_WB, phi_prev, p_WT, lengths, root, lower, upper, centres, radii, r,
                        reachable, excess, clearance, closure, fitness):  # pragma: no cover - compiled
    """Fills the ``(P,)`` outputs for ``k (P,)``; see the module docstring."""
    P, N = k.shape[0], p_WB.shape[0]
    l1, l2, l3 = lengths[0], lengths[1], lengths[2]
    sign = 1.0 if root >= 0 else -1.0
    theta = np.empty((N, 3))
    for p in range(P):
        ck, sk = math.cos(k[p]), math.sin(k[p])
        ok = True
        best = np.inf
        for n in range(N):
            bx, by = p_WB[n, 0], p_WB[n, 1]
            wx = p_WT[n, 0] - bx - l3 * ck
            wy = p_WT[n, 1] - by - l3 * sk
            c2 = (wx * wx + wy * wy - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
            if abs(c2) > 1.0 + 1e-12:
                ok = False
            c2 = min(max(c2, -1.0), 1.0)
            s2 = sign * math.sqrt(1.0 - c2 * c2)
            t2 = math.atan2(s2, c2)
            a = l1 + l2 * c2
            b = l2 * s2
            t1 = math.atan2(a * wy - b * wx, a * wx + b * wy)
            t3 = k[p] - t2 - t1
            q1 = t1 - phi_prev[n] + math.pi
            q1 = q1 - TWO_PI * math.floor(q1 / TWO_PI) - math.pi
            raw = (q1, t2, t3)
            for j in range(3):
                v = raw[j]
                if n > 0:  # unwrap against the previous sample (numpy.unwrap's rule)
                    d = v - theta[n - 1, j]
                    if abs(d) > math.pi:
                        v -= TWO_PI * math.floor(d / TWO_PI + 0.5)
                theta[n, j] = v
            if centres.shape[0] > 0:  # links: base -> elbow -> wrist -> tip
                ex, ey = bx + l1 * math.cos(t1), by + l1 * math.sin(t1)
                fx, fy = ex + l2 * math.cos(t1 + t2), ey + l2 * math.sin(t1 + t2)
                tx, ty = fx + l3 * ck, fy + l3 * sk
                xs = (bx, ex, fx, tx)
                ys = (by, ey, fy, ty)
                for s in range(3):
                    ax, ay = xs[s], ys[s]
                    abx, aby = xs[s + 1] - ax, ys[s + 1] - ay
                    ab2 = max(abx * abx + aby * aby, 1e-300)
                    for c in range(centres.shape[0]):
                        acx, acy = centres[c, 0] - ax, centres[c, 1] - ay
                        t = min(max((acx * abx + acy * aby) / ab2, 0.0), 1.0)
                        dx, dy = acx - t * abx, acy - t * aby
                        dist = math.sqrt(dx * dx + dy * dy) - radii[c]
                        if dist < best:
                            best = dist
        worst = 0.0
        close = 0.0
        total = 0.0
        for j in range(3):
            shift = TWO_PI * math.floor((theta[0, j] - lower[j]) / TWO_PI)
            for n in range(N):
                v = theta[n, j] - shift
                worst = max(worst, v - upper[j], lower[j] - v)
            close = max(close, abs(theta[N - 1, j] - theta[0, j]))
            g_prev = 0.0
            for n in range(N - 1):  # MATLAB style: forward slopes at r[:-1], trapz over r[:-1]
                slope = (theta[n + 1, j] - theta[n, j]) / (r[n + 1] - r[n])
                g = math.sqrt(1.0 + slope * slope)
                if n > 0:
                    total += 0.5 * (g + g_prev) * (r[n] - r[n - 1])
                g_prev = g
        reachable[p] = ok
        excess[p] = max(worst, 0.0)
        clearance[p] = best
        closure[p] = close
        fitness[p] = total
