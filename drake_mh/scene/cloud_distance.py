"""Exact distances between a robot's collision geometries and a point-cloud obstacle.

A cloud obstacle is the union of balls of radius ``rho`` around its points, so its signed
distance to a link geometry H is ``min_j sd_H(p_j) - rho``. Per geometry (pose from the
compiled chain of :class:`drake_mh.scene.exact.ExactDistances`), with ``c`` and ``r`` the centre
and radius of H's bounding ball and ``dn`` the distance from ``c`` to the nearest cloud point
(a k-d tree, scipy's ``cKDTree``):

* ``dn - r - rho`` bounds the value from below (a geometry far away is skipped);
* the nearest point p* has ``sd_H(p*) <= dn + r``, so it lies within ``dn + 2 r`` of ``c``: only
  the points in that ball (and within ``bound + rho + r`` when only values below ``bound``
  matter) are evaluated;
* ``sd_H`` is the closed form of :mod:`drake_mh.geometry.shapes` for sphere, capsule, box and
  cylinder links (exact), and Drake's ``QueryObject.ComputeSignedDistanceToPoint`` for
  ellipsoids and convex meshes; the witness on the link comes from Drake's point query.
"""

from __future__ import annotations

import numpy as np

__all__ = ["cloud_rows"]


def _tree(state, obstacle):
    """``(points_W (N, 3), cKDTree)`` of a cloud obstacle, kept on the obstacle state."""
    from scipy.spatial import cKDTree

    trees = state.__dict__.setdefault("cloud_trees", {})
    if obstacle.name not in trees:
        X = obstacle.X_WO
        P_W = np.ascontiguousarray(obstacle.shape.points @ X[:3, :3].T + X[:3, 3])
        trees[obstacle.name] = (P_W, cKDTree(P_W))
    return trees[obstacle.name]


def _drake_point(query, gid, p_W, threshold):
    """Drake's ``SignedDistanceToPoint`` of geometry ``gid`` at ``p_W`` (None when beyond the
    threshold)."""
    for result in query.ComputeSignedDistanceToPoint(p_W, threshold):
        if result.id_G == gid:
            return result
    return None


def cloud_rows(exact, state, q, obstacle, bound: float, per_geometry: bool = False) -> np.ndarray:
    """Rows ``(n, 11)``: geometry index g, then distance [m], point on the link (3), point on
    the cloud (3), unit normal from the cloud towards the link (3), all in W, for each robot
    geometry whose exact signed distance to the cloud ``obstacle`` is at most ``bound`` [m].

    ``exact`` (:class:`drake_mh.scene.exact.ExactDistances`) must have posed the geometries for
    ``q`` (its ``_run``). Without ``per_geometry`` the bound tightens to each value found (the
    caller wants the minimum only).
    """
    from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere

    P_W, tree = _tree(state, obstacle)
    rho = obstacle.shape.radius
    query = exact._query(q)
    rows = []
    for g, gid in enumerate(exact.gids):
        if exact.posed[g]:
            R, p = exact.R_WG[g], exact.p_WG[g]
        else:
            X = query.GetPoseInWorld(gid)
            R, p = X.rotation().matrix(), X.translation()
        c, r = R @ exact.g_float[g, 16:19] + p, exact.g_float[g, 19]
        dn = float(tree.query(c)[0])
        if dn - r - rho > bound:
            continue
        reach = dn + 2.0 * r if not np.isfinite(bound) else min(dn + 2.0 * r, bound + rho + r)
        idx = tree.query_ball_point(c, reach + 1e-12)
        if not idx:
            continue
        points = P_W[idx]
        shape = exact.scene._link_kinds[gid][1]
        if isinstance(shape, (Sphere, Box, Cylinder, Capsule)):
            sd = shape.signed_distance((points - p) @ R)
        else:  # ellipsoids, convex meshes: Drake's point query
            found = [_drake_point(query, gid, x, dn + 2.0 * r) for x in points]
            sd = np.array([np.inf if f is None else f.distance for f in found])
        j = int(np.argmin(sd))
        value = float(sd[j]) - rho
        if value > bound:
            continue
        best = points[j]
        witness = _drake_point(query, gid, best, float(sd[j]) + 1e-6)
        if witness is not None:
            gradient = np.asarray(witness.grad_W, dtype=float)
            p_link = query.GetPoseInWorld(gid) @ np.asarray(witness.p_GN, dtype=float)
        else:  # not reported by Drake (at the threshold's edge): the direction to the link's centre
            gradient = best - c
            gradient = gradient / max(np.linalg.norm(gradient), 1e-300)
            p_link = best - float(sd[j]) * gradient
        nhat = -gradient  # the cloud point's SDF gradient points away from the link
        rows.append(np.concatenate([[g, value], p_link, best + rho * nhat, nhat]))
        if not per_geometry:
            bound = min(bound, value)
    return np.array(rows, dtype=float).reshape(-1, 11)
