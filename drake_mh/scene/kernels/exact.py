"""Numba kernels behind :mod:`drake_mh.scene.exact`: one configuration's link-obstacle distances.

One call computes the world pose of every robot collision geometry from ``q`` (the compiled
chain of :mod:`drake_mh.kinematics.kernels`, tested against Drake) and then, per link geometry and
obstacle, the exact signed distance:

* sphere or capsule link vs sphere or capsule obstacle, and capsule-capsule self pairs: the
  closest points of two segments (a point is a segment of length 0) minus both radii; exact
  in penetration too (a segment has no interior);
* sphere link vs box or cylinder obstacle: the obstacle's closed-form SDF at the centre minus
  the radius (exact everywhere);
* capsule link vs box or cylinder obstacle: the golden-section search of
  :mod:`drake_mh.scene.segment_distance` along the capsule's axis; exact while the axis stays
  outside the obstacle, otherwise the pair is marked ``NEEDS_DRAKE`` (the axis's deepest point
  is not the penetration depth);
* any link vs a convex piece of a mesh (a ``HULL`` core, grown by the pieces' cover excess), and
  box, cylinder, ellipsoid and convex-hull links vs any obstacle: the certified GJK of
  :mod:`drake_mh.scene.kernels.gjk`; ``NEEDS_DRAKE`` when the cores overlap (or the search stops
  without a positive lower bound: its bound inside is no penetration depth). A search that
  stops short with a positive bound keeps that bound (never above the truth; not seen in tests).

Pruning: every pair has a cheap lower bound, the obstacle's SDF at the centre of the link
geometry's bounding sphere minus that sphere's radius (the signed distance can only grow when
a shape shrinks, and a ball's is exact). In ``min_only`` mode pairs are refined in the order of
their bound until the bound reaches the smallest distance found; otherwise a pair is skipped
only when its bound exceeds ``max_distance``.

Array layouts (built by :class:`drake_mh.scene.exact.ExactDistances`):

* ``g_int (G, 5)``: anchor frame, link kind (``LINK_*``), hull start, hull count, GJK core kind;
* ``g_float (G, 20)``: ``R_AG`` (9, row-major), ``p_AG`` (3), core dims (3), margin (radius of a
  sphere/capsule, else 0), bounding-sphere centre in G (3), bounding radius;
* ``o_int (K, 2)``: SDF kind (:mod:`drake_mh.scene.segment_distance`), GJK core kind;
* ``o_float (K, 20)``: ``R_WO`` (9), ``p_WO`` (3), SDF dims (3), core dims (3; a ``HULL``'s
  first vertex and count in ``vertices``), margin, 0;
* outputs per pair ``i = g * K + k`` then self pair ``G * K + s``: ``out (n, 10)`` = distance,
  point on the link (3), point on the other (3), unit normal from the other towards the link
  (3), all in W; ``status (n,)``.
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.kinematics.kernels import fk_jacobian_one
from drake_mh.scene.kernels import gjk
from drake_mh.scene.segment_distance import _GOLDEN, _ITERATIONS, BOX, CYLINDER, _gradient, _sdf

LINK_DRAKE, LINK_POINT, LINK_SEGMENT, LINK_GJK = 0, 1, 2, 3
"""Link kinds: left to Drake's query, sphere, capsule, any other convex shape (certified GJK)."""
SKIPPED, EXACT, NEEDS_DRAKE = 0, 1, 2


@numba.njit(cache=True)
def geometry_poses(q, parent, KR, Kp, perm, kind, qidx, g_int, g_float, R_WG, p_WG):
    """World poses ``R_WG (G, 3, 3)``, ``p_WG (G, 3)`` of the geometries; False if ``q`` is not finite."""
    for i in range(q.shape[0]):
        if not np.isfinite(q[i]):
            return False
    F = parent.shape[0]
    R = np.empty((F, 3, 3))
    p = np.empty((F, 3))
    eye = np.eye(3)
    zero = np.zeros(3)
    T = np.empty((4, 4))
    J = np.empty((6, q.shape[0]))
    fk_jacobian_one(q, parent, KR, Kp, perm, kind, qidx, -1, eye, zero, np.zeros(F, np.bool_), False, R, p, T, J)
    for g in range(g_int.shape[0]):
        a = g_int[g, 0]
        for i in range(3):
            if a < 0:
                p_WG[g, i] = g_float[g, 9 + i]
                for j in range(3):
                    R_WG[g, i, j] = g_float[g, 3 * i + j]
            else:
                p_WG[g, i] = (p[a, i] + R[a, i, 0] * g_float[g, 9] + R[a, i, 1] * g_float[g, 10]
                              + R[a, i, 2] * g_float[g, 11])
                for j in range(3):
                    R_WG[g, i, j] = (R[a, i, 0] * g_float[g, j] + R[a, i, 1] * g_float[g, 3 + j]
                                     + R[a, i, 2] * g_float[g, 6 + j])
    return True


@numba.njit(cache=True)
def _segment_ends(g, g_float, R_WG, p_WG, a, b):
    """Axis ends of a capsule link (a point twice for a sphere link), in W."""
    h = g_float[g, 12]
    for i in range(3):
        a[i] = p_WG[g, i] - h * R_WG[g, i, 2]
        b[i] = p_WG[g, i] + h * R_WG[g, i, 2]


@numba.njit(cache=True)
def closest_segments(p1, q1, p2, q2, c1, c2):
    """Closest points ``c1`` on segment p1-q1 and ``c2`` on p2-q2 (Ericson, Real-Time Collision
    Detection, sec. 5.1.9, degenerate segments included); returns their distance."""
    d10, d11, d12 = q1[0] - p1[0], q1[1] - p1[1], q1[2] - p1[2]
    d20, d21, d22 = q2[0] - p2[0], q2[1] - p2[1], q2[2] - p2[2]
    r0, r1, r2 = p1[0] - p2[0], p1[1] - p2[1], p1[2] - p2[2]
    a = d10 * d10 + d11 * d11 + d12 * d12
    e = d20 * d20 + d21 * d21 + d22 * d22
    f = d20 * r0 + d21 * r1 + d22 * r2
    eps = 1e-30
    if a <= eps and e <= eps:
        s = t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d10 * r0 + d11 * r1 + d12 * r2
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d10 * d20 + d11 * d21 + d12 * d22
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 1e-15 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    c1[0], c1[1], c1[2] = p1[0] + s * d10, p1[1] + s * d11, p1[2] + s * d12
    c2[0], c2[1], c2[2] = p2[0] + t * d20, p2[1] + t * d21, p2[2] + t * d22
    return np.sqrt((c1[0] - c2[0]) ** 2 + (c1[1] - c2[1]) ** 2 + (c1[2] - c2[2]) ** 2)


@numba.njit(cache=True)
def _golden(kind, dims, a, b):
    """:func:`drake_mh.scene.segment_distance.segment_min_sdf` without allocation (the same
    iterations and arithmetic, so the same numbers): ``(t*, sdf*)`` along a -> b (obstacle frame)."""
    a0, a1, a2 = a[0], a[1], a[2]
    d0, d1, d2 = b[0] - a0, b[1] - a1, b[2] - a2
    lo, hi = 0.0, 1.0
    t1 = hi - _GOLDEN * (hi - lo)
    t2 = lo + _GOLDEN * (hi - lo)
    f1 = _sdf(kind, dims, a0 + t1 * d0, a1 + t1 * d1, a2 + t1 * d2)
    f2 = _sdf(kind, dims, a0 + t2 * d0, a1 + t2 * d1, a2 + t2 * d2)
    for _ in range(_ITERATIONS):
        if f1 <= f2:
            hi, t2, f2 = t2, t1, f1
            t1 = hi - _GOLDEN * (hi - lo)
            f1 = _sdf(kind, dims, a0 + t1 * d0, a1 + t1 * d1, a2 + t1 * d2)
        else:
            lo, t1, f1 = t1, t2, f2
            t2 = lo + _GOLDEN * (hi - lo)
            f2 = _sdf(kind, dims, a0 + t2 * d0, a1 + t2 * d1, a2 + t2 * d2)
    best_t, best_f = (t1, f1) if f1 <= f2 else (t2, f2)
    f = _sdf(kind, dims, a0, a1, a2)
    if f < best_f:
        best_t, best_f = 0.0, f
    f = _sdf(kind, dims, a0 + d0, a1 + d1, a2 + d2)
    if f < best_f:
        best_t, best_f = 1.0, f
    return best_t, best_f


@numba.njit(cache=True)
def _normal_and_closest(kind, dims, p, f, n, c):
    """Unit normal ``n`` of a box or cylinder at ``p`` (obstacle frame, SDF value ``f``) and the
    obstacle's point ``c`` nearest to it: exact (clamping) outside, from the numerical SDF
    gradient of :mod:`drake_mh.scene.segment_distance` inside."""
    if f > 0.0:
        if kind == BOX:
            for j in range(3):
                c[j] = min(max(p[j], -dims[j]), dims[j])
        else:
            rho = np.sqrt(p[0] * p[0] + p[1] * p[1])
            scale = min(rho, dims[0]) / rho if rho > 0.0 else 0.0
            c[0], c[1] = scale * p[0], scale * p[1]
            c[2] = min(max(p[2], -dims[1]), dims[1])
        norm = np.sqrt((p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2 + (p[2] - c[2]) ** 2)
        if norm > 0.0:
            for j in range(3):
                n[j] = (p[j] - c[j]) / norm
            return
    g = _gradient(kind, dims, p)
    for j in range(3):
        n[j] = g[j]
        c[j] = p[j] - f * g[j]


@numba.njit(cache=True)
def _write(out, i, d, c_link, r_link, c_other, r_other, n):
    """Row i: distance, points pushed out of the cores by the radii along the normal n."""
    out[i, 0] = d
    for j in range(3):
        out[i, 1 + j] = c_link[j] - r_link * n[j]
        out[i, 4 + j] = c_other[j] + r_other * n[j]
        out[i, 7 + j] = n[j]


@numba.njit(cache=True)
def _unit(c_link, c_other, n):
    """``n = (c_link - c_other) / |...|`` (z when the points coincide)."""
    norm = 0.0
    for j in range(3):
        n[j] = c_link[j] - c_other[j]
        norm += n[j] * n[j]
    norm = np.sqrt(norm)
    if norm > 0.0:
        for j in range(3):
            n[j] /= norm
    else:
        n[0], n[1], n[2] = 0.0, 0.0, 1.0


@numba.njit(cache=True)
def _to_obstacle(o_float, k, x, out):
    """``out = R_WO^T (x - p_WO)``."""
    d0, d1, d2 = x[0] - o_float[k, 9], x[1] - o_float[k, 10], x[2] - o_float[k, 11]
    for i in range(3):
        out[i] = o_float[k, i] * d0 + o_float[k, 3 + i] * d1 + o_float[k, 6 + i] * d2


@numba.njit(cache=True)
def _to_world(o_float, k, x, out):
    """``out = R_WO x + p_WO``."""
    for i in range(3):
        out[i] = (o_float[k, 9 + i] + o_float[k, 3 * i] * x[0] + o_float[k, 3 * i + 1] * x[1]
                  + o_float[k, 3 * i + 2] * x[2])


@numba.njit(cache=True)
def _rotate(o_float, k, x, out):
    """``out = R_WO x``."""
    for i in range(3):
        out[i] = o_float[k, 3 * i] * x[0] + o_float[k, 3 * i + 1] * x[1] + o_float[k, 3 * i + 2] * x[2]


@numba.njit(cache=True)
def lower_bound(g, k, g_float, o_int, o_float, R_WG, p_WG, work):
    """Cheap lower bound of pair (g, k): obstacle SDF at the bounding centre minus its radius."""
    c = work[0]
    c_O = work[1]
    for i in range(3):
        c[i] = (p_WG[g, i] + R_WG[g, i, 0] * g_float[g, 16] + R_WG[g, i, 1] * g_float[g, 17]
                + R_WG[g, i, 2] * g_float[g, 18])
    _to_obstacle(o_float, k, c, c_O)
    return _sdf(o_int[k, 0], o_float[k, 12:15], c_O[0], c_O[1], c_O[2]) - g_float[g, 19]


@numba.njit(cache=True)
def pair_distance(g, k, g_int, g_float, vertices, o_int, o_float, R_WG, p_WG, out, i, work, tol):
    """Exact distance of link geometry g and obstacle k into row i of ``out``; returns the status."""
    kind = g_int[g, 1]
    sdf_kind = o_int[k, 0]
    dims = o_float[k, 12:15]
    r_link = g_float[g, 15]
    a, b, c_link, c_other, n = work[0], work[1], work[2], work[3], work[4]
    a_O, b_O, p_O, n_O = work[5], work[6], work[7], work[8]
    if (kind == LINK_POINT or kind == LINK_SEGMENT) and o_int[k, 1] != gjk.HULL:
        _segment_ends(g, g_float, R_WG, p_WG, a, b)
        if sdf_kind == BOX or sdf_kind == CYLINDER:
            _to_obstacle(o_float, k, a, a_O)
            if kind == LINK_POINT:
                f = _sdf(sdf_kind, dims, a_O[0], a_O[1], a_O[2])
                for j in range(3):
                    p_O[j] = a_O[j]
            else:
                _to_obstacle(o_float, k, b, b_O)
                t, f = _golden(sdf_kind, dims, a_O, b_O)
                for j in range(3):
                    p_O[j] = a_O[j] + t * (b_O[j] - a_O[j])
            _normal_and_closest(sdf_kind, dims, p_O, f, a_O, n_O)  # a_O: the normal in O
            _to_world(o_float, k, n_O, c_other)
            _to_world(o_float, k, p_O, c_link)
            _rotate(o_float, k, a_O, n)
            _write(out, i, f - r_link, c_link, r_link, c_other, 0.0, n)
            return EXACT if (f >= 0.0 or kind == LINK_POINT) else NEEDS_DRAKE
        # sphere or capsule obstacle: its axis in W
        h = o_float[k, 15]
        for j in range(3):
            a_O[j] = o_float[k, 9 + j] - h * o_float[k, 3 * j + 2]
            b_O[j] = o_float[k, 9 + j] + h * o_float[k, 3 * j + 2]
        core = closest_segments(a, b, a_O, b_O, c_link, c_other)
        _unit(c_link, c_other, n)
        r_other = o_float[k, 18]
        _write(out, i, core - r_link - r_other, c_link, r_link, c_other, r_other, n)
        return EXACT
    # certified GJK in the obstacle frame (a sphere or capsule link against a convex piece too:
    # its core is a point or a segment, its radius the margin r_link)
    if kind != LINK_POINT and kind != LINK_SEGMENT:
        r_link = 0.0
    R_OG = np.empty((3, 3))
    for r in range(3):
        for s in range(3):
            R_OG[r, s] = (o_float[k, r] * R_WG[g, 0, s] + o_float[k, 3 + r] * R_WG[g, 1, s]
                          + o_float[k, 6 + r] * R_WG[g, 2, s])
    for j in range(3):
        c_link[j] = p_WG[g, j]
    _to_obstacle(o_float, k, c_link, p_O)
    res = np.empty(8)
    status = gjk.gjk(g_int[g, 4], g_float[g, 12:15], R_OG, p_O, vertices, g_int[g, 2], g_int[g, 3],
                      o_int[k, 1], o_float[k, 15:18], tol, res)
    if status == gjk.INTERSECTING or (status == gjk.NOT_CONVERGED and res[0] <= tol):
        out[i, 0] = np.inf  # overlapping cores: Drake's penetration depth (its EPA)
        return NEEDS_DRAKE
    r_other = o_float[k, 18]
    _to_world(o_float, k, res[2:5], c_link)
    _to_world(o_float, k, res[5:8], c_other)
    _unit(c_link, c_other, n)
    _write(out, i, res[0] - r_other - r_link, c_link, r_link, c_other, r_other, n)
    return EXACT


@numba.njit(cache=True)
def exact_pairs(q, parent, KR, Kp, perm, kind, qidx, g_int, g_float, vertices, o_int, o_float, self_pairs,
                max_distance, min_only, tol, R_WG, p_WG, out, status, need, order):
    """Every link-obstacle pair and capsule-capsule self pair of one configuration.

    Returns:
        ``(smallest distance found, number of pairs listed in need, number of rows in order)``:
        ``need`` lists the pairs marked ``NEEDS_DRAKE`` (their row holds a value the caller
        compares with Drake's, or inf); ``order`` the ``EXACT`` rows within ``max_distance``,
        closest first (not in ``min_only`` mode). ``(nan, -1, 0)`` when ``q`` is not finite. In
        ``min_only`` mode rows of pairs whose lower bound reached the minimum are left ``SKIPPED``.
    """
    if not geometry_poses(q, parent, KR, Kp, perm, kind, qidx, g_int, g_float, R_WG, p_WG):
        return np.nan, -1, 0
    G = g_int.shape[0]
    K = o_int.shape[0]
    work = np.empty((9, 3))
    best = np.inf
    n_need = 0
    cand = np.empty(G * K, np.int64)
    bound = np.empty(G * K)
    n_cand = 0
    for s in range(self_pairs.shape[0]):
        i = G * K + s
        ga, gb = self_pairs[s, 0], self_pairs[s, 1]
        a, b, c, d = work[0], work[1], work[5], work[6]
        _segment_ends(ga, g_float, R_WG, p_WG, a, b)
        _segment_ends(gb, g_float, R_WG, p_WG, c, d)
        core = closest_segments(a, b, c, d, work[2], work[3])
        _unit(work[2], work[3], work[4])
        _write(out, i, core - g_float[ga, 15] - g_float[gb, 15], work[2], g_float[ga, 15], work[3],
               g_float[gb, 15], work[4])
        status[i] = EXACT
        best = min(best, out[i, 0])
    for g in range(G):
        link = g_int[g, 1]
        for k in range(K):
            i = g * K + k
            status[i] = SKIPPED
            if link == LINK_DRAKE:
                continue
            cheap = (link == LINK_POINT and o_int[k, 1] != gjk.HULL) or (link == LINK_SEGMENT
                                                                       and o_int[k, 1] <= gjk.SEGMENT)
            if cheap:
                status[i] = pair_distance(g, k, g_int, g_float, vertices, o_int, o_float, R_WG, p_WG, out, i,
                                          work, tol)
                best = min(best, out[i, 0])
                continue
            lb = lower_bound(g, k, g_float, o_int, o_float, R_WG, p_WG, work)
            if lb > max_distance:
                continue
            cand[n_cand] = i
            bound[n_cand] = lb
            n_cand += 1
    by_bound = np.argsort(bound[:n_cand]) if min_only else np.arange(n_cand)
    for j in range(n_cand):
        i = cand[by_bound[j]]
        if min_only and bound[by_bound[j]] >= best:
            break
        st = pair_distance(i // K, i % K, g_int, g_float, vertices, o_int, o_float, R_WG, p_WG, out, i, work, tol)
        status[i] = st
        if st == NEEDS_DRAKE:
            need[n_need] = i
            n_need += 1
        best = min(best, out[i, 0])
    n_rows = 0
    if not min_only:
        for i in range(status.shape[0]):
            if status[i] == EXACT and out[i, 0] <= max_distance:
                order[n_rows] = i
                n_rows += 1
        values = np.empty(n_rows)
        for j in range(n_rows):
            values[j] = out[order[j], 0]
        sort = np.argsort(values, kind="mergesort")
        rows = order[:n_rows].copy()
        for j in range(n_rows):
            order[j] = rows[sort[j]]
    return best, n_need, n_rows
