"""Certified GJK: the distance between two convex cores, with a proven lower bound.

Why this exists: Drake 1.51 answers mesh (convex hull), ellipsoid, box and cylinder links
against box, cylinder and capsule obstacles with GJK, measured up to 7.5 mm (mesh vs capsule)
and 16 mm (ellipsoid vs box) *optimistic*. :mod:`drake_mh.scene.exact` runs this search instead
and returns a value that is never more than the true distance.

Every shape is a *core* grown by a ball of radius ``margin`` (a sphere is a point core, a
capsule a segment core, the others have margin 0). For convex ``X`` the signed distance of
``X ⊕ B(r)`` is ``sdf_X - r`` everywhere, so ``sd(A, B) = sd(core_A, core_B) - r_A - r_B``,
in penetration too, and only the cores meet GJK (Gilbert, Johnson, Keerthi, IEEE J. Robot.
Autom. 4(2), 1988) on the Minkowski difference ``C = core_A - core_B``.

Certificate: for any unit direction ``u``, ``C`` lies in the half space ``u·c >= u·w`` with
``w = s_C(-u)`` (the support point), so the origin's signed distance to ``C`` is at least
``u·w`` — whether the origin lies outside ``C`` (distance) or inside (minus the depth, which
cannot exceed the distance to that half space's boundary). Each iteration gives such a lower
bound ``lb`` (the best is kept) and a point ``v`` of ``C`` (``|v|`` an upper bound ``ub`` of the
distance). The search stops when ``ub - lb <= tol`` and returns ``lb``: never more than the
true signed distance, at most ``tol`` less. Polytope pairs stop exactly (finitely many support
points); curved cores (cylinder rims, ellipsoids) converge geometrically.

Sub-algorithm: the point of the simplex (<= 4 points) nearest the origin, by trying every
subset (at most 15) and keeping the nearest affine projection whose barycentric weights are
all positive (the nearest point lies in the relative interior of exactly one face).

Core kinds and ``dims``: ``POINT`` (-); ``SEGMENT`` (half length along z); ``BOX`` (half sizes);
``CYLINDER`` (radius, half length along z); ``ELLIPSOID`` (semi-axes a, b, c); ``HULL``
(vertices ``vertices[start:start + count]`` in the shape frame; for core B, ``start`` and
``count`` are ``dims_b[0]`` and ``dims_b[1]``, in the same vertex array).
"""

from __future__ import annotations

import numba
import numpy as np

POINT, SEGMENT, BOX, CYLINDER, ELLIPSOID, HULL = 0, 1, 2, 3, 4, 5
SEPARATED, INTERSECTING, NOT_CONVERGED = 1, 2, 3
TOLERANCE = 1e-10
"""Gap ``ub - lb`` [m] at which the search stops (the returned value is at most this below the truth)."""
MAX_ITERATIONS = 128


@numba.njit(cache=True)
def support(kind, dims, vertices, start, count, dx, dy, dz, out):
    """Write into ``out (3,)`` a point of the core (in its own frame) farthest along ``d``."""
    if kind == POINT:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0
    elif kind == SEGMENT:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = dims[0] if dz >= 0.0 else -dims[0]
    elif kind == BOX:
        out[0] = dims[0] if dx >= 0.0 else -dims[0]
        out[1] = dims[1] if dy >= 0.0 else -dims[1]
        out[2] = dims[2] if dz >= 0.0 else -dims[2]
    elif kind == CYLINDER:
        rho = np.sqrt(dx * dx + dy * dy)
        if rho > 0.0:
            out[0] = dims[0] * dx / rho
            out[1] = dims[0] * dy / rho
        else:
            out[0] = 0.0
            out[1] = 0.0
        out[2] = dims[1] if dz >= 0.0 else -dims[1]
    elif kind == ELLIPSOID:
        ax, ay, az = dims[0] * dims[0] * dx, dims[1] * dims[1] * dy, dims[2] * dims[2] * dz
        norm = np.sqrt(ax * dx + ay * dy + az * dz)
        if norm > 0.0:
            out[0] = ax / norm
            out[1] = ay / norm
            out[2] = az / norm
        else:
            out[0] = dims[0]
            out[1] = 0.0
            out[2] = 0.0
    else:  # HULL
        best = -np.inf
        j = start
        for i in range(start, start + count):
            s = vertices[i, 0] * dx + vertices[i, 1] * dy + vertices[i, 2] * dz
            if s > best:
                best = s
                j = i
        out[0] = vertices[j, 0]
        out[1] = vertices[j, 1]
        out[2] = vertices[j, 2]


@numba.njit(cache=True)
def _support_a(kind, dims, R, p, vertices, start, count, dx, dy, dz, local, out):
    """Support point of core A posed at ``(R, p)`` in B's frame, along ``d`` (B's frame)."""
    support(kind, dims, vertices, start, count,
            R[0, 0] * dx + R[1, 0] * dy + R[2, 0] * dz,
            R[0, 1] * dx + R[1, 1] * dy + R[2, 1] * dz,
            R[0, 2] * dx + R[1, 2] * dy + R[2, 2] * dz, local)
    for i in range(3):
        out[i] = p[i] + R[i, 0] * local[0] + R[i, 1] * local[1] + R[i, 2] * local[2]


@numba.njit(cache=True)
def _nearest_on_simplex(W, n, lam):
    """Weights ``lam`` of the point of ``conv(W[:n])`` nearest the origin; returns the subset mask."""
    best = np.inf
    best_mask = 1
    idx = np.empty(4, np.int64)
    mu = np.empty(4)
    for mask in range(1, 1 << n):
        k = 0
        for i in range(n):
            if mask & (1 << i):
                idx[k] = i
                k += 1
        i0 = idx[0]
        if k == 1:
            mu[0] = 1.0
        elif k == 2:
            d0 = W[idx[1], 0] - W[i0, 0]
            d1 = W[idx[1], 1] - W[i0, 1]
            d2 = W[idx[1], 2] - W[i0, 2]
            dd = d0 * d0 + d1 * d1 + d2 * d2
            if dd <= 1e-300:
                continue
            t = -(W[i0, 0] * d0 + W[i0, 1] * d1 + W[i0, 2] * d2) / dd
            mu[0] = 1.0 - t
            mu[1] = t
        elif k == 3:
            a0, a1, a2 = W[idx[1], 0] - W[i0, 0], W[idx[1], 1] - W[i0, 1], W[idx[1], 2] - W[i0, 2]
            b0, b1, b2 = W[idx[2], 0] - W[i0, 0], W[idx[2], 1] - W[i0, 1], W[idx[2], 2] - W[i0, 2]
            g00 = a0 * a0 + a1 * a1 + a2 * a2
            g01 = a0 * b0 + a1 * b1 + a2 * b2
            g11 = b0 * b0 + b1 * b1 + b2 * b2
            r0 = -(W[i0, 0] * a0 + W[i0, 1] * a1 + W[i0, 2] * a2)
            r1 = -(W[i0, 0] * b0 + W[i0, 1] * b1 + W[i0, 2] * b2)
            det = g00 * g11 - g01 * g01
            if det <= 1e-12 * g00 * g11 or det <= 1e-300:
                continue
            s = (r0 * g11 - r1 * g01) / det
            t = (g00 * r1 - g01 * r0) / det
            mu[0] = 1.0 - s - t
            mu[1] = s
            mu[2] = t
        else:
            a0, a1, a2 = W[idx[1], 0] - W[i0, 0], W[idx[1], 1] - W[i0, 1], W[idx[1], 2] - W[i0, 2]
            b0, b1, b2 = W[idx[2], 0] - W[i0, 0], W[idx[2], 1] - W[i0, 1], W[idx[2], 2] - W[i0, 2]
            c0, c1, c2 = W[idx[3], 0] - W[i0, 0], W[idx[3], 1] - W[i0, 1], W[idx[3], 2] - W[i0, 2]
            x0, x1, x2 = b1 * c2 - b2 * c1, b2 * c0 - b0 * c2, b0 * c1 - b1 * c0  # b x c
            det = a0 * x0 + a1 * x1 + a2 * x2
            scale = (np.sqrt(a0 * a0 + a1 * a1 + a2 * a2) * np.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
                     * np.sqrt(c0 * c0 + c1 * c1 + c2 * c2))
            if abs(det) <= 1e-12 * scale or scale <= 1e-300:
                continue
            w0, w1, w2 = -W[i0, 0], -W[i0, 1], -W[i0, 2]  # solve [a b c] (s, t, u) = -W0 (Cramer)
            s = (w0 * x0 + w1 * x1 + w2 * x2) / det
            t = (a0 * (w1 * c2 - w2 * c1) + a1 * (w2 * c0 - w0 * c2) + a2 * (w0 * c1 - w1 * c0)) / det
            u = (a0 * (b1 * w2 - b2 * w1) + a1 * (b2 * w0 - b0 * w2) + a2 * (b0 * w1 - b1 * w0)) / det
            mu[0] = 1.0 - s - t - u
            mu[1] = s
            mu[2] = t
            mu[3] = u
        ok = True
        for j in range(k):
            if not mu[j] > 0.0:
                ok = False
        if not ok:
            continue
        x0 = 0.0
        x1 = 0.0
        x2 = 0.0
        for j in range(k):
            x0 += mu[j] * W[idx[j], 0]
            x1 += mu[j] * W[idx[j], 1]
            x2 += mu[j] * W[idx[j], 2]
        norm2 = x0 * x0 + x1 * x1 + x2 * x2
        if norm2 < best:
            best = norm2
            best_mask = mask
            for i in range(4):
                lam[i] = 0.0
            for j in range(k):
                lam[idx[j]] = mu[j]
    if best == np.inf:  # every subset degenerate: keep the nearest point
        j = 0
        for i in range(1, n):
            if W[i, 0] ** 2 + W[i, 1] ** 2 + W[i, 2] ** 2 < W[j, 0] ** 2 + W[j, 1] ** 2 + W[j, 2] ** 2:
                j = i
        for i in range(4):
            lam[i] = 0.0
        lam[j] = 1.0
        best_mask = 1 << j
    return best_mask


@numba.njit(cache=True)
def gjk(kind_a, dims_a, R_BA, p_BA, vertices, start, count, kind_b, dims_b, tol, out):
    """Distance between core A (pose ``R_BA (3, 3)``, ``p_BA (3,)`` in B's frame) and core B.

    Writes ``out (8,)``: the certified lower bound ``lb`` of the cores' signed distance, the
    upper bound ``ub``, and the nearest points found on A and on B (in B's frame, ``ub`` apart).

    Returns:
        ``SEPARATED`` (``ub - lb <= tol``: ``lb`` is the distance to within ``tol``, possibly
        slightly negative when the cores touch), ``INTERSECTING`` (the origin is inside the
        simplex: the cores overlap by more than ``tol``; ``lb`` is still a lower bound), or
        ``NOT_CONVERGED`` (``MAX_ITERATIONS`` or no progress; ``lb`` is still a lower bound).
    """
    W = np.empty((4, 3))
    WA = np.empty((4, 3))
    WB = np.empty((4, 3))
    lam = np.zeros(4)
    a = np.empty(3)
    b = np.empty(3)
    local = np.empty(3)
    start_b, count_b = (int(dims_b[0]), int(dims_b[1])) if kind_b == HULL else (0, 0)
    dx, dy, dz = p_BA[0], p_BA[1], p_BA[2]
    if dx * dx + dy * dy + dz * dz < 1e-30:
        dx, dy, dz = 1.0, 0.0, 0.0
    _support_a(kind_a, dims_a, R_BA, p_BA, vertices, start, count, -dx, -dy, -dz, local, a)
    support(kind_b, dims_b, vertices, start_b, count_b, dx, dy, dz, b)
    n = 1
    for i in range(3):
        WA[0, i] = a[i]
        WB[0, i] = b[i]
        W[0, i] = a[i] - b[i]
    v0, v1, v2 = W[0, 0], W[0, 1], W[0, 2]
    pa0, pa1, pa2 = a[0], a[1], a[2]
    pb0, pb1, pb2 = b[0], b[1], b[2]
    lb = -np.inf
    status = NOT_CONVERGED
    for _ in range(MAX_ITERATIONS):
        vv = v0 * v0 + v1 * v1 + v2 * v2
        vn = np.sqrt(vv)
        if vn <= 1e-300:
            status = INTERSECTING if lb < -tol else SEPARATED
            break
        _support_a(kind_a, dims_a, R_BA, p_BA, vertices, start, count, -v0, -v1, -v2, local, a)
        support(kind_b, dims_b, vertices, start_b, count_b, v0, v1, v2, b)
        w0, w1, w2 = a[0] - b[0], a[1] - b[1], a[2] - b[2]
        lower = (v0 * w0 + v1 * w1 + v2 * w2) / vn
        if lower > lb:
            lb = lower
        if vn - lb <= tol:
            status = SEPARATED
            break
        repeated = False
        for j in range(n):
            if W[j, 0] == w0 and W[j, 1] == w1 and W[j, 2] == w2:
                repeated = True
        if repeated:  # no new support point: round-off stalls the search
            break
        W[n, 0], W[n, 1], W[n, 2] = w0, w1, w2
        for i in range(3):
            WA[n, i] = a[i]
            WB[n, i] = b[i]
        n += 1
        mask = _nearest_on_simplex(W, n, lam)
        m = 0
        c0 = c1 = c2 = 0.0
        for j in range(n):
            if mask & (1 << j):
                c0 += lam[j] * W[j, 0]
                c1 += lam[j] * W[j, 1]
                c2 += lam[j] * W[j, 2]
        if c0 * c0 + c1 * c1 + c2 * c2 >= vv:  # no progress (round-off): keep the last point
            break
        v0, v1, v2 = c0, c1, c2
        pa0 = pa1 = pa2 = pb0 = pb1 = pb2 = 0.0
        for j in range(n):
            if mask & (1 << j):
                lj = lam[j]
                pa0 += lj * WA[j, 0]
                pa1 += lj * WA[j, 1]
                pa2 += lj * WA[j, 2]
                pb0 += lj * WB[j, 0]
                pb1 += lj * WB[j, 1]
                pb2 += lj * WB[j, 2]
                for i in range(3):
                    W[m, i] = W[j, i]
                    WA[m, i] = WA[j, i]
                    WB[m, i] = WB[j, i]
                m += 1
        n = m
        if n == 4:  # the origin is inside the tetrahedron
            v0 = v1 = v2 = 0.0
            status = INTERSECTING if lb < -tol else SEPARATED
            break
    ub = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if status == NOT_CONVERGED and ub - lb <= tol:
        status = SEPARATED
    out[0] = lb
    out[1] = ub
    out[2], out[3], out[4] = pa0, pa1, pa2
    out[5], out[6], out[7] = pb0, pb1, pb2
    return status
