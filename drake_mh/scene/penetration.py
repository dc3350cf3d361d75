"""Lower bounds of a geometry-obstacle signed distance where the sphere model reports penetration.

The sphere model's value for one collision geometry H and an obstacle O is
``s = min_i (sdf_O(c_i) - R_i)`` over H's spheres. Because the spheres contain H:

* if the exact signed distance ``d >= 0``, then ``s <= d`` (the closest point of H lies in a
  sphere);
* if ``d < 0``, then ``s < 0`` (a point of H inside O lies in a sphere), but ``s`` can exceed
  ``d``: ``-s`` is the obstacle's depth in *one* sphere, and O can reach deeper into H than into
  any single sphere (a ball obstacle centred on a capsule's axis between two sphere centres).

So wherever ``s < 0`` this module computes ``v <= d`` from the geometry's *core* (see
:class:`drake_mh.geometry.spheres.GeometryCore`) and the model reports ``min(s, v)``, which is never more
than ``d``:

* capsule / sphere links: ``v`` is the exact distance from the axis segment to a ball or capsule
  obstacle's core, or to a box / cylinder when the axis stays outside it (golden-section search
  of :mod:`drake_mh.scene.segment_distance`); when the axis enters a box, the separating-axis theorem
  over the box's face normals and the axis x box-edge directions, which is complete for a
  segment and a box, gives minus the exact penetration depth.
* polytope links (meshes, boxes, cylinder prisms, ellipsoid polytopes): a ball obstacle whose
  centre is inside gets its exact depth from the facet planes; a ball centred outside needs
  nothing (``s <= d`` already, as the closest point of H lies in a sphere); the same holds for a
  capsule obstacle whose axis misses the polytope (exact clipping test), and one whose axis
  meets it gets the separating-axis bound over the facet normals and axis x edge directions.
  Box and cylinder obstacles get the separating-axis bound over both polytopes' face normals
  and every edge x edge direction (complete: exact depth when they overlap, a positive
  separation when they do not, so it is applied only where negative).

A convex piece of a mesh and a point cloud get a cruder bound: a convex geometry of bounding
radius ``r_H`` cannot reach deeper than ``2 (r_H + r_O)`` into a convex piece of bounding radius
``r_O`` (translating it by the two widths along any direction separates them), nor into a ball of
a cloud of radius ``r_O``, so where a geometry's spheres report penetration its value becomes at most ``-2 (r_H + r_O)``.

A cylinder obstacle is replaced by its circumscribed 16-gon prism (it contains the cylinder,
so ``v`` stays a lower bound, up to 2 % of the radius low).

All of it is compiled (:func:`correct_clearances`: C++ in the compiled core where it is built,
numba where not): a (configuration, obstacle) pair at a time, a geometry skipped where its
bounding sphere keeps out of the obstacle, only for the configurations where some sphere
reports penetration.
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh.scene.kernels.collision import point_distance
from drake_mh.scene.kernels.exact import closest_segments
from drake_mh.scene.segment_distance import CAPSULE, SPHERE, _sdf, primitive_code, segment_min_sdf
from drake_mh.geometry.shapes import Box, Cylinder, Sphere

_PRISM_SIDES = 16


@numba.njit(cache=True)
def _sat_segment(a, b, corners, normals, edges):
    """Separating-axis value of the segment a-b against conv(corners): the largest gap over the
    face normals and the segment x edge directions (minus the penetration depth if negative)."""
    d0, d1, d2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    best = -np.inf
    for m in range(normals.shape[0] + edges.shape[0]):
        if m < normals.shape[0]:
            u0, u1, u2 = normals[m, 0], normals[m, 1], normals[m, 2]
        else:
            e = edges[m - normals.shape[0]]
            u0, u1, u2 = d1 * e[2] - d2 * e[1], d2 * e[0] - d0 * e[2], d0 * e[1] - d1 * e[0]
        norm = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        if norm <= 1e-9:
            continue
        u0, u1, u2 = u0 / norm, u1 / norm, u2 / norm
        pa = u0 * a[0] + u1 * a[1] + u2 * a[2]
        pb = u0 * b[0] + u1 * b[1] + u2 * b[2]
        lo_s, hi_s = min(pa, pb), max(pa, pb)
        lo_o, hi_o = np.inf, -np.inf
        for v in range(corners.shape[0]):
            p = u0 * corners[v, 0] + u1 * corners[v, 1] + u2 * corners[v, 2]
            lo_o = min(lo_o, p)
            hi_o = max(hi_o, p)
        best = max(best, max(lo_o - hi_s, lo_s - hi_o))
    return best


@numba.njit(cache=True)
def _segment_bound(kind, dims, R_WO, p_WO, pts, half_length, radius, corners, normals, edges):
    """A lower bound of the signed distance between a capsule core (axis z of G with
    ``half_length``, ``radius``; ``pts (4, 3)`` the origin and unit-axis tips of G in W) and the
    obstacle: against a ball or a capsule the distance of the axis to the obstacle's core
    (closest points of two segments) less both radii; against a box or a cylinder
    ``min_t sdf_O(axis(t)) - radius`` (golden section) while the axis stays outside, the
    separating-axis value against ``corners`` (box or prism, obstacle frame) once it enters."""
    a, b = np.empty(3), np.empty(3)
    for i in range(3):
        c = 0.0
        z = 0.0
        for j in range(3):
            c += R_WO[j, i] * (pts[0, j] - p_WO[j])
            z += R_WO[j, i] * (pts[3, j] - pts[0, j])
        a[i] = c - half_length * z
        b[i] = c + half_length * z
    if kind == SPHERE or kind == CAPSULE:  # the closest points of the axis and the obstacle's core
        lo, hi = np.zeros(3), np.zeros(3)
        lo[2], hi[2] = -dims[1], dims[1]  # a sphere's core is a point (dims[1] = 0)
        return closest_segments(a, b, lo, hi, np.empty(3), np.empty(3)) - dims[0] - radius
    f = segment_min_sdf(kind, dims, a, b)[1]
    if f <= 0.0:
        f = _sat_segment(a, b, corners, normals, edges)
    return f - radius


@numba.njit(cache=True, inline="always")
def _gap(u0, u1, u2, VH, VO):
    """Gap between the projections of conv(VH) and conv(VO) on the unit axis u."""
    lo_h, hi_h = np.inf, -np.inf
    for v in range(VH.shape[0]):
        p = u0 * VH[v, 0] + u1 * VH[v, 1] + u2 * VH[v, 2]
        lo_h = min(lo_h, p)
        hi_h = max(hi_h, p)
    lo_o, hi_o = np.inf, -np.inf
    for v in range(VO.shape[0]):
        p = u0 * VO[v, 0] + u1 * VO[v, 1] + u2 * VO[v, 2]
        lo_o = min(lo_o, p)
        hi_o = max(hi_o, p)
    return max(lo_o - hi_h, lo_h - hi_o)


@numba.njit(cache=True)
def _sat(VH, NH, OH, EH, VO, NO, EO, stop, certain):
    """Separating-axis lower bound of the signed distance between conv(VH) and conv(VO), or
    ``+inf`` where it cannot lower ``stop`` (then the spheres' value stands).

    Every axis gives a lower bound and the best one is kept, so the scan stops as soon as the
    best reaches ``stop`` (it can no longer lower ``min(stop, v)``; a non-negative gap also
    proves separation). Facet planes of H (``NH @ p + OH <= 0``) and face normals ``NO`` of O come
    first; the edge x edge axes (``EH`` x ``EO``) follow unless the pair is ``certain`` to
    overlap (the face bound is valid there, only looser). With all axes scanned, the best gap is
    minus the exact penetration depth.
    """
    best = -np.inf
    for m in range(NH.shape[0]):  # H's facet planes: O beyond facet m (H's side is known)
        lo_o = np.inf
        for v in range(VO.shape[0]):
            lo_o = min(lo_o, NH[m, 0] * VO[v, 0] + NH[m, 1] * VO[v, 1] + NH[m, 2] * VO[v, 2])
        best = max(best, lo_o + OH[m])
        if best >= stop:
            return np.inf
    for m in range(NO.shape[0]):
        best = max(best, _gap(NO[m, 0], NO[m, 1], NO[m, 2], VH, VO))
        if best >= stop:
            return np.inf
    if not certain:
        for e in range(EH.shape[0]):
            for f in range(EO.shape[0]):
                u0 = EH[e, 1] * EO[f, 2] - EH[e, 2] * EO[f, 1]
                u1 = EH[e, 2] * EO[f, 0] - EH[e, 0] * EO[f, 2]
                u2 = EH[e, 0] * EO[f, 1] - EH[e, 1] * EO[f, 0]
                norm = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
                if norm <= 1e-9:
                    continue
                best = max(best, _gap(u0 / norm, u1 / norm, u2 / norm, VH, VO))
                if best >= stop:
                    return np.inf
    return best


@numba.njit(cache=True)
def _segment_hits(a, b, NH, OH):
    """Whether the segment a -> b meets the polytope ``NH @ p + OH <= 0`` (clipping the
    parameter interval facet by facet)."""
    lo, hi = 0.0, 1.0
    for m in range(NH.shape[0]):
        fa = NH[m, 0] * a[0] + NH[m, 1] * a[1] + NH[m, 2] * a[2] + OH[m]
        fb = NH[m, 0] * b[0] + NH[m, 1] * b[1] + NH[m, 2] * b[2] + OH[m]
        if fb < fa:  # entering
            lo = max(lo, fa / (fa - fb))
        elif fb > fa:  # leaving
            hi = min(hi, fa / (fa - fb))
        elif fa > 0:  # parallel, outside
            return False
    return lo <= hi


@numba.njit(cache=True)
def _polytope_bound(kind, dims, R_WO, p_WO, R_WG, p_WG, VH, NH, OH, EH, excess, corners, normals, edges,
                    sphere_value, VO, NO, EO):
    """A lower bound of the signed distance between a polytope core (``VH, NH, OH, EH`` in G, at
    ``R_WG, p_WG``) and an obstacle, or ``+inf`` where the spheres' value ``sphere_value`` (< 0)
    needs no correction (module docstring); ``VO, NO, EO`` workspaces of at least the
    obstacle polytope's sizes."""
    R_GO, p_GO = np.empty((3, 3)), np.empty(3)
    for i in range(3):
        p_GO[i] = 0.0
        for j in range(3):
            p_GO[i] += R_WG[j, i] * (p_WO[j] - p_WG[j])
        for k in range(3):
            R_GO[i, k] = 0.0
            for j in range(3):
                R_GO[i, k] += R_WG[j, i] * R_WO[j, k]
    if kind == SPHERE:  # exact depth of a centre inside; one outside needs nothing
        depth = -np.inf
        for m in range(NH.shape[0]):
            depth = max(depth, NH[m, 0] * p_GO[0] + NH[m, 1] * p_GO[1] + NH[m, 2] * p_GO[2] + OH[m])
        return depth - dims[0] if depth < 0 else np.inf
    if kind == CAPSULE:  # an axis that misses H meets s <= d already, as a ball centred outside
        for i in range(3):
            VO[0, i] = p_GO[i] - dims[1] * R_GO[i, 2]
            VO[1, i] = p_GO[i] + dims[1] * R_GO[i, 2]
            EO[0, i] = VO[1, i] - VO[0, i]
        if not _segment_hits(VO[0], VO[1], NH, OH):
            return np.inf
        return _sat(VH, NH, OH, EH, VO[:2], NO[:0], EO[:1], sphere_value + dims[0], False) - dims[0]
    for v in range(corners.shape[0]):  # box, cylinder prism: both polytopes' axes
        for i in range(3):
            VO[v, i] = p_GO[i] + R_GO[i, 0] * corners[v, 0] + R_GO[i, 1] * corners[v, 1] + R_GO[i, 2] * corners[v, 2]
    for m in range(normals.shape[0]):
        for i in range(3):
            NO[m, i] = R_GO[i, 0] * normals[m, 0] + R_GO[i, 1] * normals[m, 1] + R_GO[i, 2] * normals[m, 2]
    for m in range(edges.shape[0]):
        for i in range(3):
            EO[m, i] = R_GO[i, 0] * edges[m, 0] + R_GO[i, 1] * edges[m, 1] + R_GO[i, 2] * edges[m, 2]
    return _sat(VH, NH, OH, EH, VO[:corners.shape[0]], NO[:normals.shape[0]], EO[:edges.shape[0]], sphere_value,
                sphere_value < -excess)


@numba.njit(cache=True, inline="always")
def _sdf_at(kind, d, R, p, x, y, z):
    """Signed distance of the world point (x, y, z) to an obstacle at ``R, p`` (dims ``d``)."""
    dx, dy, dz = x - p[0], y - p[1], z - p[2]
    return _sdf(kind, d, R[0, 0] * dx + R[1, 0] * dy + R[2, 0] * dz, R[0, 1] * dx + R[1, 1] * dy + R[2, 1] * dz,
                R[0, 2] * dx + R[1, 2] * dy + R[2, 2] * dz)


@numba.njit(cache=True)
def _centre(p, R, c):
    """``p + R c`` as three numbers (a sphere centre in W from its geometry's pose)."""
    return (p[0] + R[0, 0] * c[0] + R[0, 1] * c[1] + R[0, 2] * c[2], p[1] + R[1, 0] * c[0] + R[1, 1] * c[1]
            + R[1, 2] * c[2], p[2] + R[2, 0] * c[0] + R[2, 1] * c[1] + R[2, 2] * c[2])


def correct_clearances(values, *arrays) -> None:
    """:func:`_correct_clearances` (the same arguments) in the compiled core ``drake_mh._native``
    where it is built (``cpp/penetration.hpp``, the same arithmetic: nothing compiled at call
    time), in the numba kernel where it is not or ``DRAKE_MH_COMPILED_CORE=0`` (read at each call)."""
    core = compiled_core()
    (_correct_clearances if core is None else core.correct_clearances)(values, *arrays)


@numba.njit(cache=True)
def _correct_clearances(values, points_W, radii, c_G, g_bound, g_start, g_kind, half_length, radius, VH, v_start, NH,
                        OH, f_start, EH, e_start, excess, kinds, R_WO, p_WO, dims, corners, n_corners, normals,
                        n_normals, edges, n_edges):
    """``values (n, K)`` in place: each negative one (the sphere model's clearance to obstacle k,
    or any negative number to have it computed) becomes ``min_g min(s_g, v_g)`` over the
    geometries g whose spheres' value ``s_g`` is negative, ``v_g`` the lower bound of g
    (:func:`_segment_bound`, :func:`_polytope_bound`); ``+inf`` if there is none.

    A geometry whose bounding sphere (about its origin, radius ``g_bound``) keeps out of the
    obstacle is skipped: its ``s_g >= 0`` (signed distances are 1-Lipschitz), so it cannot hold
    a negative minimum. ``points_W (n, 4G, 3)`` (:func:`core_points`) give each geometry's
    pose, and with it the world centres of its spheres (``c_G (S, 3)`` in the geometry frame);
    the geometries' arrays are those of :func:`core_arrays`, the obstacles' those of
    :func:`drake_mh.scene.batch.obstacle_arrays` and :func:`obstacle_polytopes`.
    """
    n, K, G = values.shape[0], values.shape[1], g_kind.shape[0]
    VO, NO, EO = np.empty((max(corners.shape[1], 2), 3)), np.empty((normals.shape[1], 3)), np.empty(
        (max(edges.shape[1], 1), 3))
    R_WG, p_WG = np.empty((G, 3, 3)), np.empty((G, 3))
    for r in range(n):
        for g in range(G):
            for i in range(3):
                p_WG[g, i] = points_W[r, 4 * g, i]
                for c in range(3):
                    R_WG[g, i, c] = points_W[r, 4 * g + 1 + c, i] - points_W[r, 4 * g, i]
        for k in range(K):
            if not values[r, k] < 0.0:
                continue
            if kinds[k] > CAPSULE:  # a convex piece or a cloud: the depth bound of the module docstring
                r_O = dims[k, 2] if kinds[k] == 4 else dims[int(dims[k, 0]), 0]
                best = np.inf
                for g in range(G):
                    s_g = np.inf
                    for s in range(g_start[g], g_start[g + 1]):
                        x, y, z = _centre(p_WG[g], R_WG[g], c_G[s])
                        s_g = min(s_g, point_distance(k, kinds, R_WO, p_WO, dims, x, y, z) - radii[s])
                    if s_g < 0.0:
                        best = min(best, s_g, -2.0 * (g_bound[g] + r_O))
                values[r, k] = best
                continue
            kind, d, R, p = kinds[k], dims[k], R_WO[k], p_WO[k]
            ck, nk, ek = corners[k, :n_corners[k]], normals[k, :n_normals[k]], edges[k, :n_edges[k]]
            best = np.inf
            for g in range(G):
                if _sdf_at(kind, d, R, p, p_WG[g, 0], p_WG[g, 1], p_WG[g, 2]) >= g_bound[g]:
                    continue
                s_g = np.inf
                for s in range(g_start[g], g_start[g + 1]):
                    x, y, z = _centre(p_WG[g], R_WG[g], c_G[s])
                    s_g = min(s_g, _sdf_at(kind, d, R, p, x, y, z) - radii[s])
                if not s_g < 0.0:
                    continue
                if g_kind[g] == 0:  # SEGMENT (drake_mh.geometry.spheres)
                    v_g = _segment_bound(kind, d, R, p, points_W[r, 4 * g:4 * g + 4], half_length[g], radius[g], ck,
                                         nk, ek)
                else:
                    v_g = _polytope_bound(kind, d, R, p, R_WG[g], p_WG[g], VH[v_start[g]:v_start[g + 1]],
                                          NH[f_start[g]:f_start[g + 1]], OH[f_start[g]:f_start[g + 1]],
                                          EH[e_start[g]:e_start[g + 1]], excess[g], ck, nk, ek, s_g, VO, NO, EO)
                best = min(best, s_g, v_g)
            values[r, k] = best


@functools.lru_cache(maxsize=256)
def _obstacle_polytope(shape):
    """``(vertices_O (V, 3), face normals_O (F, 3), edge directions_O (E, 3))`` of a box, or of
    the prism with ``_PRISM_SIDES`` sides circumscribing a cylinder (it contains the cylinder);
    empty for a sphere or a capsule (their cores are a point and a segment)."""
    if isinstance(shape, Box):
        h = 0.5 * np.asarray(shape.size)
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
        return corners, np.eye(3), np.eye(3)
    if not isinstance(shape, Cylinder):
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))
    k = _PRISM_SIDES
    angles = 2.0 * np.pi * (np.arange(k) + 0.5) / k  # corner directions; faces at multiples of 2pi/k
    ring = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(k)]) * (shape.radius / np.cos(np.pi / k))
    half = np.array([0.0, 0.0, 0.5 * shape.length])
    corners = np.vstack([ring - half, ring + half])
    face = 2.0 * np.pi * np.arange(k // 2) / k  # k/2 directions, both signs are tried
    normals = np.vstack([[0.0, 0.0, 1.0], np.column_stack([np.cos(face), np.sin(face), np.zeros(k // 2)])])
    edges = np.vstack([[0.0, 0.0, 1.0], np.column_stack([-np.sin(angles[: k // 2] + np.pi / k),
                                                         np.cos(angles[: k // 2] + np.pi / k), np.zeros(k // 2)])])
    return corners, normals, edges


def obstacle_polytopes(obstacles) -> tuple:
    """``(corners (K, V, 3), n_corners (K,), normals (K, F, 3), n_normals, edges (K, E, 3),
    n_edges)``: each obstacle's :func:`_obstacle_polytope` in its frame, zero-padded."""
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.geometry.mesh import Mesh

    none = _obstacle_polytope(Sphere(1.0))  # a mesh's pieces and a cloud: bounded without polytopes
    polys = [p for o in obstacles for p in ([none] * len(convex_pieces(o.shape)) if isinstance(o.shape, Mesh)
                                            else [_obstacle_polytope(o.shape)])]
    out = []
    for i in range(3):
        counts = np.array([len(p[i]) for p in polys], dtype=np.int64)
        packed = np.zeros((len(polys), max(counts, default=0), 3))
        for k, p in enumerate(polys):
            packed[k, :len(p[i])] = p[i]
        out += [packed, counts]
    return tuple(out)


def core_arrays(model) -> tuple:
    """The geometries of a :class:`drake_mh.geometry.spheres.SphereModel` as :func:`correct_clearances`
    reads them: ``(radii (S,), c_G (S, 3), g_bound (G,), g_start (G+1,), g_kind, half_length, radius,
    VH, v_start, NH, OH, f_start, EH, e_start, excess)``: the sphere centres in their geometry's
    frame, each geometry's bounding radius about its origin, the polytopes' vertices, facets and
    edges (in G) stacked."""
    starts, kind, half_length, radius = model.core_arrays
    cores = model.geometries

    def stacked(name, width):
        parts = [np.asarray(getattr(c, name), dtype=float).reshape(-1, *width) for c in cores]
        return (np.ascontiguousarray(np.concatenate(parts)) if parts else np.zeros((0, *width)),
                np.r_[0, np.cumsum([len(p) for p in parts])].astype(np.int64))

    (VH, v_start), (NH, f_start), (OH, _), (EH, e_start) = (stacked("vertices_G", (3,)), stacked("normals_G", (3,)),
                                                            stacked("offsets", ()), stacked("edges_G", (3,)))
    g_start = np.r_[starts, model.num_spheres].astype(np.int64)
    radii = np.ascontiguousarray(model.radii, dtype=float)
    c_G = np.empty((model.num_spheres, 3))  # the centres in their geometry's frame
    g_bound = np.empty(len(cores))
    for g, core in enumerate(cores):
        sl = slice(g_start[g], g_start[g + 1])
        c_G[sl] = (model.centres_B[sl] - core.X_BG[:3, 3]) @ core.X_BG[:3, :3]
        g_bound[g] = (np.linalg.norm(c_G[sl], axis=1) + radii[sl]).max(initial=0.0)
    return (radii, c_G, g_bound, g_start, kind.astype(np.int64), half_length.astype(float), radius.astype(float),
            VH, v_start, NH, OH, f_start, EH, e_start, np.array([c.excess for c in cores], dtype=float))


@numba.njit(cache=True)
def _segment_bounds(kind, dims, R_WO, p_WO, pts, half_length, radius, corners, normals, edges):
    """:func:`_segment_bound` of each row of ``pts (n, 4, 3)``."""
    out = np.empty(pts.shape[0])
    for m in range(pts.shape[0]):
        out[m] = _segment_bound(kind, dims, R_WO, p_WO, pts[m], half_length[m], radius[m], corners, normals, edges)
    return out


@numba.njit(cache=True)
def _polytope_bounds(kind, dims, R_WO, p_WO, R_WG, p_WG, VH, NH, OH, EH, excess, corners, normals, edges,
                     sphere_value):
    """:func:`_polytope_bound` of each pose ``R_WG (n, 3, 3), p_WG (n, 3)``."""
    VO, NO, EO = np.empty((max(corners.shape[0], 2), 3)), np.empty((normals.shape[0], 3)), np.empty(
        (max(edges.shape[0], 1), 3))
    out = np.empty(R_WG.shape[0])
    for m in range(R_WG.shape[0]):
        out[m] = _polytope_bound(kind, dims, R_WO, p_WO, R_WG[m], p_WG[m], VH, NH, OH, EH, excess, corners, normals,
                                 edges, sphere_value[m], VO, NO, EO)
    return out


def segment_lower_bound(half_length, radius, pts_W, obstacle) -> np.ndarray:
    """``v (n,)`` <= the signed distance [m] between capsules (``half_length (n,)``, ``radius (n,)``,
    axis z of G; ``pts_W (n, 4, 3)`` the origin and unit-axis tips of G in W) and an obstacle
    (module docstring)."""
    kind, dims = primitive_code(obstacle.shape)
    corners, normals, edges = _obstacle_polytope(obstacle.shape)
    R_WO, p_WO = obstacle.X_WO[:3, :3].copy(), obstacle.X_WO[:3, 3].copy()
    return _segment_bounds(kind, dims, R_WO, p_WO, np.ascontiguousarray(pts_W, dtype=float),
                           np.ascontiguousarray(half_length, dtype=float), np.ascontiguousarray(radius, dtype=float),
                           corners, normals, edges)


def polytope_lower_bound(core, R_WG: np.ndarray, p_WG: np.ndarray, obstacle, sphere_value: np.ndarray) -> np.ndarray:
    """``v (n,)`` <= the signed distance [m] between a polytope core (a
    :class:`drake_mh.geometry.spheres.GeometryCore`) at poses ``R_WG (n, 3, 3), p_WG (n, 3)`` and an
    obstacle; ``+inf`` where the sphere value needs no correction (module docstring).

    Args:
        sphere_value: ``(n,)`` the spheres' value for this geometry (< 0); below ``-core.excess``
            the pair certainly overlaps, and the edge x edge axes are skipped (the face-normal
            bound is valid, only looser).
    """
    kind, dims = primitive_code(obstacle.shape)
    corners, normals, edges = _obstacle_polytope(obstacle.shape)
    R_WO, p_WO = obstacle.X_WO[:3, :3].copy(), obstacle.X_WO[:3, 3].copy()
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (core.vertices_G, core.normals_G, core.offsets,
                                                               core.edges_G)]
    return _polytope_bounds(kind, dims, R_WO, p_WO, np.ascontiguousarray(R_WG, dtype=float),
                            np.ascontiguousarray(p_WG, dtype=float), *arrays, float(core.excess), corners, normals,
                            edges, np.ascontiguousarray(sphere_value, dtype=float))


def core_points(model) -> tuple[list, np.ndarray]:
    """Link names ``(4G,)`` and offsets ``(4G, 3)``: each geometry's origin and its origin plus
    each unit axis, in the link frame (compile them once; their world positions give X_WG)."""
    links, offsets = [], []
    for core in model.geometries:
        R, p = core.X_BG[:3, :3], core.X_BG[:3, 3]
        links.extend([core.link] * 4)
        offsets.extend([p, p + R[:, 0], p + R[:, 1], p + R[:, 2]])
    return links, np.asarray(offsets, dtype=float).reshape(-1, 3)


__all__ = ["segment_lower_bound", "polytope_lower_bound", "correct_clearances", "core_arrays", "core_points",
           "obstacle_polytopes"]
