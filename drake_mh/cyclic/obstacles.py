"""Circular obstacles in the arm's plane and link (segment) clearances.

The cyclic paper's eq. (6) asks the links ``(x_link, y_link)`` not to intersect the obstacle
area; its 12-DOF case has circles of radius 10 cm at (95, 15), (145, 65), (40, -15) cm.
Links are line segments joint to joint (the paper's model); ``link_radius`` adds the
thickness of a real link (the bundled planar URDFs use capsules of 0.025 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["CircleObstacle", "segment_clearance"]


@dataclass(frozen=True)
class CircleObstacle:
    """A disc in the arm's plane: ``centre`` (x, y) [m], ``radius`` [m]."""

    centre: tuple[float, float]
    radius: float

    def __post_init__(self):
        if len(self.centre) != 2 or not all(math.isfinite(float(c)) for c in self.centre):
            raise InvalidArgument(f"CircleObstacle.centre must be a finite (x, y) in metres, got {self.centre!r}")
        if not (math.isfinite(float(self.radius)) and float(self.radius) > 0):
            raise InvalidArgument(f"CircleObstacle.radius must be > 0 [m], got {self.radius!r}")


def segment_clearance(points, obstacles, link_radius: float = 0.0) -> np.ndarray:
    """Smallest clearance between the segments of a polyline and every obstacle.

    Args:
        points: ``(..., K, 2)`` polyline vertices [m] (e.g. base, elbow, wrist, tip of a
            3-link component); segments join consecutive vertices.
        obstacles: sequence of :class:`CircleObstacle`.
        link_radius: half thickness of the links [m] (0: the paper's line links).

    Returns:
        ``(...)`` the minimum over segments and obstacles of ``distance(segment, centre) -
        radius - link_radius`` [m]; ``+inf`` without obstacles. Negative means collision.
    """
    points = np.asarray(points, dtype=float)
    shape = points.shape[:-2]
    if not obstacles:
        return np.full(shape, np.inf)
    flat = np.ascontiguousarray(points.reshape(-1, points.shape[-2], 2))
    centres = np.array([o.centre for o in obstacles], dtype=float).reshape(-1, 2)
    radii = np.array([o.radius for o in obstacles], dtype=float) + float(link_radius)
    out = np.empty(len(flat))
    _clearance_kernel(flat, centres, radii, out)
    return out.reshape(shape)


@numba.njit(cache=True, nogil=True)
def _clearance_kernel(points, centres, radii, out):  # pragma: no cover - compiled
    """out[m] = min over segments s and circles c of |segment(points[m, s:s+2]) - c| - r_c."""
    M, K = points.shape[0], points.shape[1]
    for m in range(M):
        best = np.inf
        for s in range(K - 1):
            ax, ay = points[m, s, 0], points[m, s, 1]
            abx, aby = points[m, s + 1, 0] - ax, points[m, s + 1, 1] - ay
            ab2 = max(abx * abx + aby * aby, 1e-300)
            for c in range(centres.shape[0]):
                acx, acy = centres[c, 0] - ax, centres[c, 1] - ay
                t = min(max((acx * abx + acy * aby) / ab2, 0.0), 1.0)
                dx, dy = acx - t * abx, acy - t * aby
                d = np.sqrt(dx * dx + dy * dy) - radii[c]
                if d < best:
                    best = d
        out[m] = best
