"""Circular obstacles in the arm's plane and link (segment) clearances.

The cyclic paper's eq. (6) asks the links ``(x_link, y_link)`` not to intersect the obstacle
area; its 12-DOF case has circles of radius 10 cm at (95, 15), (145, 65), (40, -15) cm.
Links are line segments joint to joint (the paper's model); ``link_radius`` adds the
thickness of a real link (the bundled planar URDFs use capsules of 0.025 m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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
    out = np.full(points.shape[:-2], np.inf)
    if not obstacles:
        return out
    a = points[..., :-1, :]
    ab = points[..., 1:, :] - a
    ab2 = np.maximum(np.sum(ab * ab, axis=-1), 1e-300)
    for obstacle in obstacles:
        c = np.asarray(obstacle.centre, dtype=float)
        s = np.clip(np.sum((c - a) * ab, axis=-1) / ab2, 0.0, 1.0)
        closest = a + s[..., None] * ab
        dist = np.hypot(closest[..., 0] - c[0], closest[..., 1] - c[1])
        out = np.minimum(out, np.min(dist, axis=-1) - float(obstacle.radius) - float(link_radius))
    return out
