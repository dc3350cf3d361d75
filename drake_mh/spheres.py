"""A conservative sphere model of a robot, derived from its Drake collision geometry.

Metaheuristics evaluate clearance for whole populations, so the hot path cannot call Drake's
exact distance per configuration. :class:`SphereModel` covers every collision shape of every
link with spheres (a sphere by itself, capsules and cylinders by spheres along the axis, boxes
by a grid), so that

    clearance_spheres(q) <= clearance_exact(q) <= clearance_spheres(q) + bound

for every configuration: the union of the spheres *contains* the geometry (the model never
reports more clearance than Drake), and every sphere point lies within ``bound`` of the
geometry (the model is at most ``bound`` pessimistic). ``bound`` is computed per link
(:func:`excess`: exact for capsules, a Lipschitz-safe sampled bound for cylinders and boxes)
and checked against Drake in the tests. These inequalities hold for non-negative clearance;
in penetration both are negative (every collision Drake sees, the spheres see).

Covering rules (shape frame G, axis z), for a tolerance ``tol``:

* capsule (r, L): ``n = ceil(L / s)`` intervals with ``s = 2·sqrt((r + tol)² − r²)``, centres at
  the ``n + 1`` interval ends, radius ``sqrt(r² + (L / 2n)²)`` — every capsule point is within
  that radius of a centre (perpendicular distance <= r, axial <= L / 2n); excess <= tol.
* cylinder (r, L): ``n`` slabs of thickness ``h = L / n``, one sphere per slab centre with radius
  ``sqrt(r² + (h/2)²)``; the spheres bulge past the flat caps by up to about r, so cylinders
  are covered less tightly than capsules (prefer capsules for links).
* box: a grid of cells of edge <= 2·tol, each covered by its circumscribed sphere (excess up to
  about √3·tol).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.shapes import Box, Capsule, Cylinder, Sphere, from_drake

DEFAULT_TOLERANCE = 0.01
"""Default excess radius [m] allowed when covering capsules (bound of the pessimism)."""


def _fibonacci_directions(n: int = 4000) -> np.ndarray:
    """``(n, 3)`` nearly uniform unit vectors (for sampling sphere surfaces)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def cover_shape(shape, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres ``(centres_G (S, 3), radii (S,))`` whose union contains ``shape``.

    Args:
        shape: a :mod:`drake_mh.shapes` shape in its frame G.
        tolerance: target excess radius [m] (see the module docstring for each shape).
    """
    if isinstance(shape, Sphere):
        return np.zeros((1, 3)), np.array([shape.radius])
    if isinstance(shape, Capsule):
        r, L = shape.radius, shape.length
        spacing = 2.0 * np.sqrt((r + tolerance) ** 2 - r ** 2)
        n = max(1, int(np.ceil(L / spacing))) if L > 0 else 0
        if n == 0:
            return np.zeros((1, 3)), np.array([r])
        z = np.linspace(-0.5 * L, 0.5 * L, n + 1)
        radius = np.hypot(r, 0.5 * L / n)
        return np.column_stack([np.zeros_like(z), np.zeros_like(z), z]), np.full(n + 1, radius)
    if isinstance(shape, Cylinder):
        r, L = shape.radius, shape.length
        spacing = 2.0 * np.sqrt((r + tolerance) ** 2 - r ** 2)
        n = max(1, int(np.ceil(L / spacing)))
        h = L / n
        z = -0.5 * L + h * (np.arange(n) + 0.5)
        return np.column_stack([np.zeros(n), np.zeros(n), z]), np.full(n, np.hypot(r, 0.5 * h))
    if isinstance(shape, Box):
        size = np.asarray(shape.size)
        cell = 2.0 * tolerance  # cell edge; circumscribed radius = cell·√3/2
        counts = np.maximum(1, np.ceil(size / cell).astype(int))
        edges = size / counts
        axes = [-0.5 * s + e * (np.arange(c) + 0.5) for s, e, c in zip(size, edges, counts)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
        return grid, np.full(len(grid), 0.5 * np.linalg.norm(edges))
    raise InvalidArgument(f"cannot cover shape {shape!r}")


def excess(shape, centres_G: np.ndarray, radii: np.ndarray, directions=None) -> float:
    """Upper bound [m] on the distance from any point of the spheres to ``shape``.

    Exact for spheres and capsules (centres on the axis: ``max(R - r)``). For cylinders and
    boxes the sphere surfaces are sampled along ``directions`` and, because the distance is
    1-Lipschitz, ``R`` times the sampling's angular spacing is added, so the value is still a
    bound.
    """
    if isinstance(shape, (Sphere, Capsule)):
        return float(max(0.0, np.max(radii - shape.radius)))
    directions = _fibonacci_directions() if directions is None else directions
    spacing = np.sqrt(4.0 * np.pi / len(directions))  # rad, >= the lattice's covering radius
    pts = centres_G[:, None, :] + radii[:, None, None] * directions[None, :, :]
    sampled = shape.signed_distance(pts).max(axis=1) + radii * spacing
    return float(max(0.0, sampled.max()))


@dataclass(frozen=True)
class SphereModel:
    """Spheres fixed to the robot's links that cover its collision geometry.

    Attributes:
        links: ``(S,)`` link name of each sphere.
        centres_B: ``(S, 3)`` sphere centres in their link frames [m].
        radii: ``(S,)`` radii [m].
        bound: the model is at most this pessimistic [m] (max over links of ``link_bound``).
        link_bound: link name -> pessimism bound of that link's spheres [m].
        tolerance: the covering tolerance used [m].
    """

    links: tuple
    centres_B: np.ndarray
    radii: np.ndarray
    bound: float
    link_bound: dict = field(default_factory=dict)
    tolerance: float = DEFAULT_TOLERANCE

    @property
    def num_spheres(self) -> int:
        return len(self.links)

    @classmethod
    def from_robot(cls, robot, tolerance: float = DEFAULT_TOLERANCE) -> SphereModel:
        """Cover every proximity geometry of ``robot`` (read from its SceneGraph).

        Raises:
            InvalidArgument: non-positive tolerance.
            UnsupportedGeometry: a link uses a mesh or another unsupported shape.
        """
        from pydrake.geometry import Role

        tolerance = float(tolerance)
        if not np.isfinite(tolerance) or tolerance <= 0:
            raise InvalidArgument(f"sphere-model tolerance must be a positive length in metres, got {tolerance}")
        inspector = robot.scene_graph.model_inspector()
        directions = _fibonacci_directions()
        links, centres, radii, link_bound = [], [], [], {}
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            frame_id = inspector.GetFrameId(gid)
            if frame_id == inspector.world_frame_id():
                continue  # anchored geometry is scenery, not robot
            body = robot.plant.GetBodyFromFrameId(frame_id)
            if body is None:
                continue
            shape = from_drake(inspector.GetShape(gid))
            c_G, r = cover_shape(shape, tolerance)
            X_BG = inspector.GetPoseInFrame(gid).GetAsMatrix4()
            c_B = c_G @ X_BG[:3, :3].T + X_BG[:3, 3]
            link_bound[body.name()] = max(link_bound.get(body.name(), 0.0), excess(shape, c_G, r, directions))
            links.extend([body.name()] * len(r))
            centres.append(c_B)
            radii.append(r)
        if not links:
            return cls((), np.zeros((0, 3)), np.zeros(0), 0.0, {}, tolerance)
        return cls(tuple(links), np.vstack(centres), np.concatenate(radii),
                   max(link_bound.values()), link_bound, tolerance)
