"""Exact signed distance between a capsule and a convex primitive (sphere, box, cylinder, capsule).

Why this exists: Drake 1.51 computes capsule-vs-box and capsule-vs-cylinder signed distances
with GJK. Measured on the Panda's capsules against a box and a cylinder (400 random
configurations, ~6,700 pairs each): the error is below 1e-5 m for 99 % of the pairs, but rare
outliers are up to **6.7 mm** (box) and 0.47 mm (cylinder), always *optimistic* (Drake reports
more clearance than there is). :class:`drake_mh.scene.Scene` therefore refines those pairs here.

Method: a capsule is the set of points within ``r`` of a segment ``a + t (b - a)``, so its
distance to a convex set O is ``min_t sdf_O(a + t (b - a)) - r``. The signed distance function of
a convex set is convex, so along the segment it is unimodal, and a golden-section search over
``t in [0, 1]`` (90 iterations: the bracket shrinks below 1e-18) finds the minimum to machine
precision. Closest points follow from the numerical gradient of the SDF. In penetration the
value is ``min_t sdf(t) - r`` (minus the depth of the deepest axis point, minus r), which can
differ from Drake's penetration depth; callers take the smaller of the two (conservative).
"""

from __future__ import annotations

import numba
import numpy as np

SPHERE, BOX, CYLINDER, CAPSULE = 0, 1, 2, 3
_GOLDEN = 0.6180339887498949
_ITERATIONS = 90


@numba.njit(cache=True)
def _sdf(kind, dims, x, y, z):
    """Signed distance of the point (x, y, z), in the obstacle frame, to the primitive.

    The scalar, compiled twin of the vectorized ``signed_distance`` methods of
    :mod:`drake_mh.geometry.shapes` (the golden-section search calls it ~100 times per pair); the
    tests check the two against each other through dense sampling.

    dims: sphere (r, 0, 0); box (half x, half y, half z); cylinder (r, half length, 0);
    capsule (r, half length, 0).
    """
    if kind == SPHERE:
        return np.sqrt(x * x + y * y + z * z) - dims[0]
    if kind == BOX:
        dx, dy, dz = abs(x) - dims[0], abs(y) - dims[1], abs(z) - dims[2]
        ox, oy, oz = max(dx, 0.0), max(dy, 0.0), max(dz, 0.0)
        return np.sqrt(ox * ox + oy * oy + oz * oz) + min(max(dx, max(dy, dz)), 0.0)
    if kind == CYLINDER:
        dr = np.sqrt(x * x + y * y) - dims[0]
        da = abs(z) - dims[1]
        orr, oa = max(dr, 0.0), max(da, 0.0)
        return np.sqrt(orr * orr + oa * oa) + min(max(dr, da), 0.0)
    zc = min(max(z, -dims[1]), dims[1])
    return np.sqrt(x * x + y * y + (z - zc) * (z - zc)) - dims[0]


@numba.njit(cache=True)
def segment_min_sdf(kind, dims, a, b):
    """``(t*, sdf*)``: the minimum of the primitive's SDF along the segment a -> b (obstacle frame)."""
    lo, hi = 0.0, 1.0
    d = b - a
    t1 = hi - _GOLDEN * (hi - lo)
    t2 = lo + _GOLDEN * (hi - lo)
    f1 = _sdf(kind, dims, a[0] + t1 * d[0], a[1] + t1 * d[1], a[2] + t1 * d[2])
    f2 = _sdf(kind, dims, a[0] + t2 * d[0], a[1] + t2 * d[1], a[2] + t2 * d[2])
    for _ in range(_ITERATIONS):
        if f1 <= f2:
            hi, t2, f2 = t2, t1, f1
            t1 = hi - _GOLDEN * (hi - lo)
            f1 = _sdf(kind, dims, a[0] + t1 * d[0], a[1] + t1 * d[1], a[2] + t1 * d[2])
        else:
            lo, t1, f1 = t1, t2, f2
            t2 = lo + _GOLDEN * (hi - lo)
            f2 = _sdf(kind, dims, a[0] + t2 * d[0], a[1] + t2 * d[1], a[2] + t2 * d[2])
    best_t, best_f = (t1, f1) if f1 <= f2 else (t2, f2)
    for t in (0.0, 1.0):  # the ends, in case the minimum sits exactly there
        f = _sdf(kind, dims, a[0] + t * d[0], a[1] + t * d[1], a[2] + t * d[2])
        if f < best_f:
            best_t, best_f = t, f
    return best_t, best_f


@numba.njit(cache=True)
def _gradient(kind, dims, p):
    g = np.empty(3)
    h = 1e-7
    for i in range(3):
        q1 = p.copy()
        q2 = p.copy()
        q1[i] += h
        q2[i] -= h
        g[i] = (_sdf(kind, dims, q1[0], q1[1], q1[2]) - _sdf(kind, dims, q2[0], q2[1], q2[2])) / (2 * h)
    n = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    if n > 0:
        g /= n
    return g


def primitive_code(shape) -> tuple[int, np.ndarray] | None:
    """``(kind, dims)`` of a :mod:`drake_mh.geometry.shapes` shape for the kernels, or ``None``."""
    from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere

    if isinstance(shape, Sphere):
        return SPHERE, np.array([shape.radius, 0.0, 0.0])
    if isinstance(shape, Box):
        return BOX, 0.5 * np.asarray(shape.size, dtype=float)
    if isinstance(shape, Cylinder):
        return CYLINDER, np.array([shape.radius, 0.5 * shape.length, 0.0])
    if isinstance(shape, Capsule):
        return CAPSULE, np.array([shape.radius, 0.5 * shape.length, 0.0])
    return None


def capsule_distance(X_WC: np.ndarray, radius: float, length: float, X_WO: np.ndarray, shape):
    """Signed distance between a capsule (pose ``X_WC``, axis z) and a primitive at ``X_WO``.

    Returns:
        ``(distance [m], p_W_capsule (3,), p_W_obstacle (3,), nhat_W (3,))`` with the normal
        pointing from the obstacle towards the capsule; ``None`` for unsupported shapes.
    """
    code = primitive_code(shape)
    if code is None:
        return None
    kind, dims = code
    R_WO, p_WO = X_WO[:3, :3], X_WO[:3, 3]
    half = 0.5 * length * X_WC[:3, 2]
    a_O = R_WO.T @ (X_WC[:3, 3] - half - p_WO)
    b_O = R_WO.T @ (X_WC[:3, 3] + half - p_WO)
    t, f = segment_min_sdf(kind, dims, a_O, b_O)
    p_O = a_O + t * (b_O - a_O)
    n_O = _gradient(kind, dims, p_O)
    on_obstacle_O = p_O - f * n_O
    on_capsule_O = p_O - radius * n_O
    return (float(f - radius), R_WO @ on_capsule_O + p_WO, R_WO @ on_obstacle_O + p_WO, R_WO @ n_O)
