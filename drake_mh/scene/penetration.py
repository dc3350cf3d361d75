"""Lower bounds of a geometry-obstacle signed distance where the sphere model reports penetration.

The sphere model's value for one collision geometry H and an obstacle O is
``s = min_i (sdf_O(c_i) - R_i)`` over H's spheres. Because the spheres contain H:

* if the exact signed distance ``d >= 0``, then ``s <= d`` (the closest point of H lies in a
  sphere);
* if ``d < 0``, then ``s < 0`` (a point of H inside O lies in a sphere), but ``s`` can exceed
  ``d``: ``-s`` is the obstacle's depth in *one* sphere, and O can reach deeper into H than into
  any single sphere (a ball obstacle centred on a capsule's axis between two sphere centres).

So wherever ``s < 0`` this module computes ``v <= d`` from the geometry's *core* (see
:class:`drake_mh.spheres.GeometryCore`) and the model reports ``min(s, v)``, which is never more
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

A cylinder obstacle is replaced by its circumscribed 16-gon prism (it contains the cylinder,
so ``v`` stays a lower bound, up to 2 % of the radius low).
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from drake_mh.scene.segment_distance import CAPSULE, SPHERE, primitive_code, segment_min_sdf
from drake_mh.shapes import Box, Capsule, Sphere

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
def _segment_core_kernel(kind, dims, R_WO, p_WO, pts, half_length, radius, corners, normals, edges):
    """For each pair m, a lower bound of the signed distance between the capsule core (axis z of
    G with ``half_length[m]``, ``radius[m]``; ``pts (m, 4, 3)`` the origin and unit-axis tips of G
    in W) and the obstacle: ``min_t sdf_O(axis(t)) - radius`` while the axis stays outside the
    obstacle, the separating-axis value against ``corners`` (box or prism) once it enters."""
    m_count = pts.shape[0]
    out = np.empty(m_count)
    a = np.empty(3)
    b = np.empty(3)
    for m in range(m_count):
        for i in range(3):
            c = 0.0
            z = 0.0
            for j in range(3):
                c += R_WO[j, i] * (pts[m, 0, j] - p_WO[j])
                z += R_WO[j, i] * (pts[m, 3, j] - pts[m, 0, j])
            a[i] = c - half_length[m] * z
            b[i] = c + half_length[m] * z
        f = segment_min_sdf(kind, dims, a, b)[1]
        if f <= 0.0 and corners.shape[0] > 0:
            f = _sat_segment(a, b, corners, normals, edges)
        out[m] = f - radius[m]
    return out


@functools.lru_cache(maxsize=256)
def _obstacle_polytope(shape):
    """``(vertices_O (V, 3), face normals_O (F, 3), edge directions_O (E, 3))`` of a box, or of
    the prism with ``_PRISM_SIDES`` sides circumscribing a cylinder (it contains the cylinder)."""
    if isinstance(shape, Box):
        h = 0.5 * np.asarray(shape.size)
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
        return corners, np.eye(3), np.eye(3)
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


def _to_obstacle_frame(R_WG, p_WG, obstacle):
    """``(R_GO (n, 3, 3), p_GO (n, 3))``: the obstacle's pose in each geometry frame."""
    R_WO, p_WO = obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
    R_GO = np.einsum("nji,jk->nik", R_WG, R_WO)  # R_WG^T R_WO
    p_GO = np.einsum("nji,nj->ni", R_WG, p_WO - p_WG)
    return R_GO, p_GO


def segment_lower_bound(half_length, radius, pts_W, obstacle) -> np.ndarray:
    """``v (n,)`` <= the signed distance [m] between capsules (``half_length (n,)``, ``radius (n,)``,
    axis z of G; ``pts_W (n, 4, 3)`` the origin and unit-axis tips of G in W) and an obstacle
    (module docstring)."""
    shape = obstacle.shape
    kind, dims = primitive_code(shape)
    if kind in (SPHERE, CAPSULE):  # segment to a point / segment core: exact
        corners = normals = edges = np.zeros((0, 3))
    else:  # the axis may enter the obstacle: separating axes (complete for a box)
        corners, normals, edges = _obstacle_polytope(shape)
    return _segment_core_kernel(kind, dims, obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3],
                                np.ascontiguousarray(pts_W), half_length, radius, corners, normals, edges)


def _segment_hits_polytope(a, b, normals, offsets) -> np.ndarray:
    """Whether each segment ``a_n -> b_n`` meets the polytope ``normals @ p + offsets <= 0``
    (clipping the parameter interval facet by facet)."""
    fa = a @ normals.T + offsets
    fb = b @ normals.T + offsets
    with np.errstate(divide="ignore", invalid="ignore"):
        t = fa / (fa - fb)  # where the segment crosses each facet plane
    lo = np.where(fb < fa, t, -np.inf).max(axis=1, initial=0.0)  # entering facets
    hi = np.where(fb > fa, t, np.inf).min(axis=1, initial=1.0)  # leaving facets
    parallel_out = ((fa == fb) & (fa > 0)).any(axis=1)
    return (np.maximum(lo, 0.0) <= np.minimum(hi, 1.0)) & ~parallel_out


@numba.njit(cache=True, inline="always")
def _gap(u0, u1, u2, VH, VO, n):
    """Gap between the projections of conv(VH) and conv(VO[n]) on the unit axis u."""
    lo_h, hi_h = np.inf, -np.inf
    for v in range(VH.shape[0]):
        p = u0 * VH[v, 0] + u1 * VH[v, 1] + u2 * VH[v, 2]
        lo_h = min(lo_h, p)
        hi_h = max(hi_h, p)
    lo_o, hi_o = np.inf, -np.inf
    for v in range(VO.shape[1]):
        p = u0 * VO[n, v, 0] + u1 * VO[n, v, 1] + u2 * VO[n, v, 2]
        lo_o = min(lo_o, p)
        hi_o = max(hi_o, p)
    return max(lo_o - hi_h, lo_h - hi_o)


@numba.njit(cache=True)
def _polytope_sat_kernel(VH, NH, OH, EH, VO, NO, EO, sphere_value, certain):
    """Separating-axis lower bound of the signed distance between conv(VH) and each conv(VO[n]),
    or ``+inf`` where it cannot lower ``sphere_value[n]`` (then the spheres' value stands).

    Every axis gives a lower bound and the best one is kept, so the scan stops as soon as the
    best reaches ``sphere_value`` (it can no longer lower ``min(sphere_value, v)``; a
    non-negative gap also proves separation). Facet planes of H (``NH @ p + OH <= 0``) and face
    normals of O come first; the edge x edge axes follow unless the pair is ``certain`` to
    overlap (its sphere value below minus the link's excess: the face bound is valid there,
    only looser). With all axes scanned, the best gap is minus the exact penetration depth.
    """
    out = np.empty(VO.shape[0])
    for n in range(VO.shape[0]):
        stop = sphere_value[n]
        best = -np.inf
        for m in range(NH.shape[0]):  # H's facet planes: O beyond facet m (H's side is known)
            lo_o = np.inf
            for v in range(VO.shape[1]):
                lo_o = min(lo_o, NH[m, 0] * VO[n, v, 0] + NH[m, 1] * VO[n, v, 1] + NH[m, 2] * VO[n, v, 2])
            best = max(best, lo_o + OH[m])
            if best >= stop:
                break
        if best < stop:
            for m in range(NO.shape[1]):
                best = max(best, _gap(NO[n, m, 0], NO[n, m, 1], NO[n, m, 2], VH, VO, n))
                if best >= stop:
                    break
        if best < stop and not certain[n]:
            for e in range(EH.shape[0]):
                for f in range(EO.shape[1]):
                    u0 = EH[e, 1] * EO[n, f, 2] - EH[e, 2] * EO[n, f, 1]
                    u1 = EH[e, 2] * EO[n, f, 0] - EH[e, 0] * EO[n, f, 2]
                    u2 = EH[e, 0] * EO[n, f, 1] - EH[e, 1] * EO[n, f, 0]
                    norm = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
                    if norm <= 1e-9:
                        continue
                    best = max(best, _gap(u0 / norm, u1 / norm, u2 / norm, VH, VO, n))
                    if best >= stop:
                        break
                if best >= stop:
                    break
        out[n] = np.inf if best >= stop else best
    return out


def polytope_lower_bound(core, R_WG: np.ndarray, p_WG: np.ndarray, obstacle, sphere_value: np.ndarray) -> np.ndarray:
    """``v (n,)`` <= the signed distance [m] between a polytope core (a
    :class:`drake_mh.spheres.GeometryCore`) at poses ``R_WG, p_WG`` and an obstacle; ``+inf``
    where the sphere value needs no correction (module docstring).

    Args:
        sphere_value: ``(n,)`` the spheres' value for this geometry (< 0); below ``-core.excess``
            the pair certainly overlaps, and the edge x edge axes are skipped (the face-normal
            bound is valid, only looser).
    """
    shape = obstacle.shape
    R_GO, p_GO = _to_obstacle_frame(R_WG, p_WG, obstacle)
    N, off = core.normals_G, core.offsets
    if isinstance(shape, Sphere):
        depth = (p_GO @ N.T + off).max(axis=1)
        return np.where(depth < 0, depth - shape.radius, np.inf)
    certain = sphere_value < -core.excess
    n = len(p_GO)
    if isinstance(shape, Capsule):
        # a capsule whose axis misses P meets s <= d already (as a ball centred outside P does)
        half = 0.5 * shape.length * R_GO[:, :, 2]
        a, b = p_GO - half, p_GO + half
        hits = _segment_hits_polytope(a, b, N, off)
        v = np.full(n, np.inf)
        if hits.any():
            seg = np.ascontiguousarray(np.stack([a[hits], b[hits]], axis=1))
            direction = np.ascontiguousarray((seg[:, 1] - seg[:, 0])[:, None, :])
            v[hits] = _polytope_sat_kernel(core.vertices_G, N, off, core.edges_G, seg, np.zeros((len(seg), 0, 3)),
                                           direction, sphere_value[hits] + shape.radius,
                                           np.zeros(len(seg), np.bool_)) - shape.radius
        return v
    corners, normals, edges = _obstacle_polytope(shape)
    corners_G = np.ascontiguousarray(np.einsum("nij,vj->nvi", R_GO, corners) + p_GO[:, None, :])
    normals_G = np.ascontiguousarray(np.einsum("nij,mj->nmi", R_GO, normals))
    edges_G = np.ascontiguousarray(np.einsum("nij,mj->nmi", R_GO, edges))
    return _polytope_sat_kernel(core.vertices_G, N, off, core.edges_G, corners_G, normals_G, edges_G,
                                np.ascontiguousarray(sphere_value, dtype=float), certain)


def core_points(model) -> tuple[list, np.ndarray]:
    """Link names ``(4G,)`` and offsets ``(4G, 3)``: each geometry's origin and its origin plus
    each unit axis, in the link frame (compile them once; their world positions give X_WG)."""
    links, offsets = [], []
    for core in model.geometries:
        R, p = core.X_BG[:3, :3], core.X_BG[:3, 3]
        links.extend([core.link] * 4)
        offsets.extend([p, p + R[:, 0], p + R[:, 1], p + R[:, 2]])
    return links, np.asarray(offsets, dtype=float).reshape(-1, 3)


def corrected_min(model, per_sphere: np.ndarray, geometry_points_W: np.ndarray, obstacle) -> np.ndarray:
    """``(n,)`` the model's clearance to ``obstacle`` with penetrating geometries corrected.

    Args:
        model: the :class:`drake_mh.spheres.SphereModel`.
        per_sphere: ``(n, S)`` per-sphere signed distances to the obstacle [m].
        geometry_points_W: ``(n, 4G, 3)`` world positions of :func:`core_points`.
        obstacle: the :class:`drake_mh.scene.Obstacle`.
    """
    from drake_mh.spheres import SEGMENT

    starts, kind, half_length, radius = model.core_arrays
    per_geometry = np.minimum.reduceat(per_sphere, starts, axis=1)  # (n, G)
    rows, geoms = np.nonzero(per_geometry < 0)
    if not len(rows):
        return per_geometry.min(axis=1)
    pts = geometry_points_W.reshape(len(per_sphere), -1, 4, 3)[rows, geoms]  # (m, 4, 3)
    seg = kind[geoms] == SEGMENT
    if seg.all():
        v = segment_lower_bound(half_length[geoms], radius[geoms], pts, obstacle)
    else:
        v = np.full(len(rows), np.inf)
        if seg.any():
            v[seg] = segment_lower_bound(half_length[geoms[seg]], radius[geoms[seg]], pts[seg], obstacle)
        p_WG = pts[:, 0]
        R_WG = np.stack([pts[:, 1] - p_WG, pts[:, 2] - p_WG, pts[:, 3] - p_WG], axis=2)
        for g in np.unique(geoms[~seg]):
            sel = geoms == g
            v[sel] = polytope_lower_bound(model.geometries[g], R_WG[sel], p_WG[sel], obstacle,
                                          per_geometry[rows[sel], g])
    per_geometry[rows, geoms] = np.minimum(per_geometry[rows, geoms], v)
    return per_geometry.min(axis=1)


__all__ = ["segment_lower_bound", "polytope_lower_bound", "corrected_min", "core_points"]
