"""Cover one convex collision shape with spheres: the union contains the shape, with a proven excess.

The sphere model (:mod:`drake_mh.geometry.spheres`) calls :func:`cover` once per collision geometry. For a
shape H it returns spheres ``B(c_j, R_j)`` and a number ``excess`` such that

* **containment**: ``H`` is a subset of the union of the spheres;
* **excess**: every point of every sphere lies within ``excess`` of ``H``.

How each shape is covered (frame G of the shape, axis z as in Drake), for a tolerance ``tol``:

* sphere: itself (excess 0).
* capsule (r, L): ``n = ceil(L / s)`` intervals with ``s = 2 sqrt((r + tol)^2 - r^2)``, centres at
  the ``n + 1`` interval ends on the axis, radius ``sqrt(r^2 + (L / 2n)^2)``: every capsule point
  is within that radius of a centre, and the excess is exactly ``radius - r <= tol``.
* every other shape is first replaced by a convex polytope P that contains it: a box is one, a
  cylinder becomes the circumscribed prism (``k`` sides, ``r sec(pi/k) - r <= tol / 10``), an
  ellipsoid the linear image of a polytope circumscribing the unit ball, a Drake ``Convex`` /
  ``Mesh`` its convex hull. P is within ``hausdorff`` of the shape (0 for boxes and hulls).
  :func:`cover_polytope` then covers P:

  1. **cells**: an octree over P's bounding cube. A cell (centre x, circumradius rho) is dropped
     when ``max_k (n_k . x + d_k) > rho`` or ``u . x - h_P(u) > rho`` for the direction u from the
     nearest vertex (both are lower bounds of the distance from x to P, so the cell misses P).
     A cell is kept as a *target* when it lies inside P with ``rho <= (depth(x) + tol) / 2``, or
     when ``rho <= 0.45 tol``; otherwise it is split in 8. The kept cells contain P. A kept
     cell whose centre lies outside facet plane k by s > 0 meets P only in the cap of its
     circumscribed ball behind that plane, which lies in the ball of radius
     ``sqrt(rho^2 - s^2)`` centred at the centre's projection onto the plane: that smaller
     ball is the target (it reaches at most rho past P instead of 2 rho).
  2. **candidates**: for each target a centre c inside P (the cell centre, or for a centre outside P
     a projection onto P's facets pulled radially inside) with radius ``depth(c) + tol``, where
     ``depth(c) = -max_k (n_k . c + d_k)`` is the exact distance from c to P's boundary. The ball
     ``B(c, depth(c))`` lies in P, so every point of ``B(c, depth(c) + tol)`` is within tol of P.
  3. **greedy set cover**: a candidate covers a target when ``|x - c| + rho <= R`` (the target
     ball lies in the sphere). The candidate covering most uncovered targets
     is taken until all are covered; picks whose targets the others all cover are dropped
     (latest first), and each sphere shrinks to the largest ``|x - c| + rho`` of the targets
     assigned to it. A target no candidate covers (rare, a poor
     projection) gets its own sphere ``B(c, |x - c| + rho)``.

  The excess of a sphere ``B(c, R)`` with c in P is at most ``R - depth(c)``; the covering's
  ``excess`` is the largest of these plus ``hausdorff``. Both properties are exact consequences
  of the construction (no sampling), checked by the tests against dense samples.

Trade-off: a sphere of radius ``depth + tol`` covers a patch of radius about
``sqrt(2 depth tol)`` of a flat face and a short piece of a sharp edge, so the count grows with
the surface area and edge length over the tolerance: at 1 cm, 20-130 spheres per link of
example-robot-data's Panda (790 in all; UR5: 806, up to 319 for its long upper arm), at 2 cm
about a third as many. Capsule links need only ``sqrt(L^2 / (8 r tol))`` or so. The batched
clearance costs one sphere-obstacle distance per sphere and configuration, so the tolerance
sets both the pessimism and the cost.
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere

_TARGET_RHO = 0.45
"""Boundary cells are split until their circumradius is at most this fraction of ``tol``."""

def _fibonacci_directions(n: int) -> np.ndarray:
    """``(n, 3)`` nearly uniform unit vectors."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def circumscribed_polytope(shape, tolerance: float) -> tuple[ConvexPolytope, float]:
    """A polytope P containing ``shape`` and ``hausdorff``: every point of P is that close to it.

    Args:
        shape: :class:`Box`, :class:`Cylinder`, :class:`Ellipsoid` or :class:`ConvexPolytope`.
        tolerance: the covering tolerance [m]; P is made within ``tolerance / 10`` of the shape.
    """
    if isinstance(shape, ConvexPolytope):
        return shape, 0.0
    if isinstance(shape, Box):
        h = 0.5 * np.asarray(shape.size)
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
        return ConvexPolytope(corners), 0.0
    if isinstance(shape, Cylinder):
        r, half = shape.radius, 0.5 * shape.length
        # k-gon with apothem r contains the circle; its corners are r / cos(pi / k) out
        k = max(8, int(np.ceil(np.pi / np.arccos(1.0 / (1.0 + 0.1 * tolerance / r)))))
        k = min(k, 256)
        angles = 2.0 * np.pi * np.arange(k) / k
        ring = np.column_stack([np.cos(angles), np.sin(angles)]) * (r / np.cos(np.pi / k))
        corners = np.vstack([np.column_stack([ring, np.full(k, z)]) for z in (-half, half)])
        return ConvexPolytope(corners), r / np.cos(np.pi / k) - r
    if isinstance(shape, Ellipsoid):
        axes = np.array([shape.a, shape.b, shape.c])
        n = 64
        while True:
            unit = ConvexPolytope(_fibonacci_directions(n))
            inner = float(np.min(-unit.offsets))  # the hull contains the ball of this radius
            vertices = unit.vertices / inner  # now contains the unit ball
            hausdorff = float(axes.max() * (np.linalg.norm(vertices, axis=1).max() - 1.0))
            if hausdorff <= 0.1 * tolerance or n >= 4096:
                return ConvexPolytope(vertices * axes), hausdorff
            n *= 2
    raise InvalidArgument(f"no circumscribed polytope for shape {shape!r}")


@numba.njit(cache=True)
def _halfspace_max(x, normals, offsets, out_k):
    """``max_k (n_k . x_m + d_k)`` for each row of ``x (M, 3)`` (and its argmax in ``out_k``)."""
    out = np.empty(x.shape[0])
    for m in range(x.shape[0]):
        best, arg = -np.inf, 0
        for k in range(normals.shape[0]):
            v = normals[k, 0] * x[m, 0] + normals[k, 1] * x[m, 1] + normals[k, 2] * x[m, 2] + offsets[k]
            if v > best:
                best, arg = v, k
        out[m] = best
        out_k[m] = arg
    return out


def _hs(poly: ConvexPolytope, x: np.ndarray, want_k: bool = False):
    """Compiled :meth:`ConvexPolytope.halfspace_distance` of ``x (M, 3)`` (and the facet index)."""
    k = np.empty(len(x), np.int64)
    values = _halfspace_max(np.ascontiguousarray(x, dtype=float), poly.normals, poly.offsets, k)
    return (values, k) if want_k else values


def _inside_point(poly: ConvexPolytope) -> np.ndarray:
    """A point strictly inside the polytope (the mean of its vertices)."""
    return poly.vertices.mean(axis=0)


def _project_inside(poly: ConvexPolytope, x: np.ndarray, iterations: int = 12) -> np.ndarray:
    """Points of P near ``x (M, 3)``: repeated projection onto the most violated facet plane,
    then a radial pull towards an interior point so that the result is inside P for sure."""
    c = x.copy()
    for _ in range(iterations):
        values, k = _hs(poly, c, want_k=True)
        viol = np.maximum(values, 0.0)
        if not viol.any():
            break
        c -= viol[:, None] * poly.normals[k]
    o = _inside_point(poly)
    d = c - o
    # largest t in [0, 1] with o + t d inside: n.(o + t d) + off <= 0 for every facet
    along = d @ poly.normals.T
    room = -(o @ poly.normals.T + poly.offsets)  # > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        limits = np.where(along > 0, room / along, np.inf)
    t = np.minimum(1.0, limits.min(axis=1)) * (1.0 - 1e-12)
    return o + t[:, None] * d


def _target_cells(poly: ConvexPolytope, tol: float):
    """Octree cells ``(centres (T, 3), rho (T,))`` whose union contains P (module docstring, step 1)."""
    lo, hi = poly.vertices.min(axis=0), poly.vertices.max(axis=0)
    edge = float((hi - lo).max()) * (1.0 + 1e-9)
    x = (0.5 * (lo + hi))[None]
    rho_min = _TARGET_RHO * tol
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    centres, rhos = [], []
    while len(x):
        rho = 0.5 * np.sqrt(3.0) * edge
        hs = _hs(poly, x)
        keep = hs <= rho
        outside = np.flatnonzero(keep & (hs > 0))
        if len(outside):  # separating direction from the nearest vertex: a second lower bound
            gap = _vertex_gap(x[outside], poly.vertices)
            keep[outside[gap > rho]] = False
        x, hs = x[keep], hs[keep]
        done = (rho <= rho_min) | ((hs <= -rho) & (rho <= 0.5 * (tol - hs)))
        centres.append(x[done])
        rhos.append(np.full(int(done.sum()), rho))
        x = (x[~done][:, None, :] + 0.25 * edge * signs[None]).reshape(-1, 3)
        edge *= 0.5
    return np.vstack(centres), np.concatenate(rhos)


@numba.njit(cache=True)
def _vertex_gap(x, vertices):
    """For each point: ``u . x - max_v u . v`` with u the unit direction from its nearest vertex
    (a lower bound of its distance to the hull of ``vertices``)."""
    out = np.empty(x.shape[0])
    for m in range(x.shape[0]):
        best, arg = np.inf, 0
        for v in range(vertices.shape[0]):
            d = ((x[m, 0] - vertices[v, 0]) ** 2 + (x[m, 1] - vertices[v, 1]) ** 2
                 + (x[m, 2] - vertices[v, 2]) ** 2)
            if d < best:
                best, arg = d, v
        n = np.sqrt(best)
        if n == 0.0:
            out[m] = 0.0
            continue
        u0 = (x[m, 0] - vertices[arg, 0]) / n
        u1 = (x[m, 1] - vertices[arg, 1]) / n
        u2 = (x[m, 2] - vertices[arg, 2]) / n
        support = -np.inf
        for v in range(vertices.shape[0]):
            support = max(support, u0 * vertices[v, 0] + u1 * vertices[v, 1] + u2 * vertices[v, 2])
        out[m] = u0 * x[m, 0] + u1 * x[m, 1] + u2 * x[m, 2] - support
    return out


def _ranges(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """``concatenate([arange(a, b) for a, b in zip(starts, ends)])`` without a Python loop."""
    lengths = ends - starts
    total = int(lengths.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    first = np.repeat(starts - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
    return first + np.arange(total)


def _covering_pairs(cand, reach, x, rho):
    """``(i, j, |x_j - c_i|)`` for every candidate i and target j with ``|x_j - c_i| + rho_j <= reach_i``.

    Candidates are queried in groups of similar reach (one radius for all would pair the small
    boundary spheres with every target within the largest reach)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(x)
    rho_min = float(rho.min())
    groups = np.floor(np.log(reach / reach.min()) / np.log(1.25)).astype(np.int64)
    ii, jj, dd = [], [], []
    for g in np.unique(groups):
        members = np.flatnonzero(groups == g)
        sub = cKDTree(cand[members]).sparse_distance_matrix(tree, float(reach[members].max() - rho_min),
                                                            output_type="ndarray")
        i, j, d = members[sub["i"]], sub["j"], sub["v"]
        ok = d + rho[j] <= reach[i]
        ii.append(i[ok])
        jj.append(j[ok])
        dd.append(d[ok])
    return np.concatenate(ii), np.concatenate(jj), np.concatenate(dd)


def _prune(by_cand, rho: np.ndarray, chosen: np.ndarray, covered: np.ndarray):
    """Drop greedy picks whose targets the other picks all cover (latest picks first, they
    cover least), then shrink each kept sphere to the targets assigned to it.

    Returns:
        ``(chosen (P,), radii (P,))``.
    """
    sub = by_cand[chosen]  # (P, T) rows of the picked candidates, data = distance + 1
    times = np.bincount(sub.indices, minlength=sub.shape[1])  # picks covering each target
    keep = np.ones(len(chosen), bool)
    for k in range(len(chosen) - 1, -1, -1):
        targets = sub.indices[sub.indptr[k]:sub.indptr[k + 1]]
        if np.all(times[targets] >= 2):
            keep[k] = False
            times[targets] -= 1
    sub = sub[np.flatnonzero(keep)].tocsc()
    # each covered target goes to one kept pick that covers it; a pick's radius is the largest
    # |x - c| + rho of its targets
    targets = np.flatnonzero(covered)
    owner_pos = sub.indptr[targets]  # first kept pick covering the target
    owner = sub.indices[owner_pos]
    need = sub.data[owner_pos] - 1.0 + rho[targets]
    radii = np.zeros(int(keep.sum()))
    np.maximum.at(radii, owner, need)
    used = radii > 0  # a pick that owns no target is not needed
    return chosen[keep][used], radii[used]


def cover_polytope(poly: ConvexPolytope, tolerance: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Spheres ``(centres (S, 3), radii (S,))`` whose union contains ``poly``, and their excess [m].

    See the module docstring (steps 1-3) for the construction and why both properties hold.
    """
    tol = float(tolerance)
    x, rho = _target_cells(poly, tol)
    # a cell whose centre is outside facet plane k by s > 0 meets P only in the cap of its ball
    # behind that plane, which lies in the ball of radius sqrt(rho^2 - s^2) around the centre's
    # projection onto the plane: cover that smaller ball (it reaches at most rho past P, not 2 rho)
    s_out, k = _hs(poly, x, want_k=True)
    cap = s_out > 0
    x[cap] -= s_out[cap, None] * poly.normals[k[cap]]
    rho[cap] = np.sqrt(np.maximum(rho[cap] ** 2 - s_out[cap] ** 2, 0.0))
    hs = _hs(poly, x)
    cand_all = x.copy()
    out = hs > -1e-12
    if out.any():
        cand_all[out] = _project_inside(poly, x[out])
    # neighbouring boundary cells project to nearby points: keep one candidate per (tol/2)-cell
    keep = np.unique(np.round(cand_all / (0.5 * tol)).astype(np.int64), axis=0, return_index=True)[1]
    cand = cand_all[keep]
    depth = np.maximum(-_hs(poly, cand), 0.0)
    reach = depth + tol
    i, j, dist = _covering_pairs(cand, reach, x, rho)
    n_cand, n_target = len(cand), len(x)
    # pairs by candidate (CSR) and by target (CSC); +1 keeps zero distances stored
    from scipy.sparse import csr_matrix

    by_cand = csr_matrix((dist + 1.0, (i, j)), shape=(n_cand, n_target))
    by_target = by_cand.tocsc()
    counts = np.diff(by_cand.indptr).astype(np.int64)
    covered = np.zeros(n_target, bool)
    chosen, radii = [], []
    while True:
        best = int(counts.argmax())
        if counts[best] <= 0:
            break
        sl = slice(by_cand.indptr[best], by_cand.indptr[best + 1])
        targets = by_cand.indices[sl]
        fresh = ~covered[targets]
        new_targets = targets[fresh]
        covered[new_targets] = True
        chosen.append(best)
        radii.append(float(np.max(by_cand.data[sl][fresh] - 1.0 + rho[new_targets])))
        rows = _ranges(by_target.indptr[new_targets], by_target.indptr[new_targets + 1])
        counts -= np.bincount(by_target.indices[rows], minlength=n_cand)
    chosen, radii = _prune(by_cand, rho, np.asarray(chosen, np.int64), covered)
    centres, radii, depths = [cand[chosen]], [radii], [depth[chosen]]
    left = np.flatnonzero(~covered)
    if len(left):  # a target no candidate covers (a poor projection): its own sphere
        c_left = cand_all[left]
        centres.append(c_left)
        radii.append(np.linalg.norm(x[left] - c_left, axis=1) + rho[left])
        depths.append(np.maximum(-_hs(poly, c_left), 0.0))
    centres, radii, depths = np.vstack(centres), np.concatenate(radii), np.concatenate(depths)
    return centres, radii, float(np.max(np.maximum(radii - depths, 0.0)))


def cover(shape, tolerance: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Spheres ``(centres_G (S, 3), radii (S,))`` whose union contains ``shape``, and the excess [m].

    Args:
        shape: a :mod:`drake_mh.geometry.shapes` shape in its frame G (robot collision geometry).
        tolerance: the excess is at most this [m] for every shape (polytopes are covered with
            ``tolerance - hausdorff``).

    Raises:
        InvalidArgument: non-positive tolerance or an unknown shape.
    """
    tolerance = float(tolerance)
    if not np.isfinite(tolerance) or tolerance <= 0:
        raise InvalidArgument(f"sphere-model tolerance must be a positive length in metres, got {tolerance}")
    if isinstance(shape, Sphere):
        return np.zeros((1, 3)), np.array([shape.radius]), 0.0
    if isinstance(shape, Capsule):
        r, L = shape.radius, shape.length
        if L <= 0:
            return np.zeros((1, 3)), np.array([r]), 0.0
        spacing = 2.0 * np.sqrt((r + tolerance) ** 2 - r ** 2)
        n = max(1, int(np.ceil(L / spacing)))
        z = np.linspace(-0.5 * L, 0.5 * L, n + 1)
        radius = float(np.hypot(r, 0.5 * L / n))
        return np.column_stack([np.zeros_like(z), np.zeros_like(z), z]), np.full(n + 1, radius), radius - r
    poly, hausdorff = circumscribed_polytope(shape, tolerance)
    centres, radii, excess = cover_polytope(poly, tolerance - hausdorff)
    return centres, radii, excess + hausdorff
