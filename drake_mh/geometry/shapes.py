"""Primitive shapes: obstacles and the robot's collision geometry.

Each shape is a frozen dataclass expressed in its own frame O (centred at the origin; the axis
of cylinders and capsules is z, as in Drake) with

* ``to_drake()``: the matching ``pydrake.geometry`` shape (for exact distances in SceneGraph);
* ``signed_distance(p_O)``: vectorized signed distance ``(...)`` [m] from points ``p_O (..., 3)``
  expressed in O — positive outside, negative inside (minus the depth to the surface).

These closed forms are used by the batched distance queries of the sphere model; the exact
robot-obstacle distances always come from Drake.

A robot's collision geometry may also be an :class:`Ellipsoid` or a :class:`ConvexPolytope`
(Drake's ``Convex`` and ``Mesh``, both used by Drake's proximity queries as their convex hull).
These two are not obstacle shapes: the sphere model covers them (:mod:`drake_mh.geometry.sphere_cover`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import SceneError, UnsupportedGeometry


def _positive(name: str, value: float) -> float:
    if isinstance(value, (bool, str, bytes)) or value is None or np.iscomplexobj(value):
        raise SceneError(f"{name} must be a positive finite length in metres, got {value!r}")
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise SceneError(f"{name} must be a positive finite length in metres, got {value!r}") from None
    if not np.isfinite(value) or value <= 0:
        raise SceneError(f"{name} must be a positive finite length in metres, got {value}")
    return value


@dataclass(frozen=True)
class Sphere:
    """Sphere of ``radius`` [m] centred at the frame origin."""

    radius: float

    def __post_init__(self):
        object.__setattr__(self, "radius", _positive("Sphere radius", self.radius))

    def to_drake(self):
        from pydrake.geometry import Sphere as DrakeSphere

        return DrakeSphere(self.radius)

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        return np.linalg.norm(p_O, axis=-1) - self.radius


@dataclass(frozen=True, init=False)
class Box:
    """Box of full side lengths ``size = (x, y, z)`` [m] centred at the frame origin.

    ``Box((x, y, z))`` and ``Box(x, y, z)`` are the same box.
    """

    size: tuple

    def __init__(self, *size):
        object.__setattr__(self, "size", size[0] if len(size) == 1 else size)
        self.__post_init__()

    def __post_init__(self):
        try:
            size = np.asarray(self.size, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise SceneError(f"Box size must be 3 side lengths (x, y, z) in metres, got {self.size!r}") from None
        if size.shape != (3,):
            raise SceneError(f"Box size must be 3 side lengths (x, y, z) in metres, got {self.size!r}")
        object.__setattr__(self, "size", tuple(_positive("Box side", s) for s in size))

    def to_drake(self):
        from pydrake.geometry import Box as DrakeBox

        return DrakeBox(*self.size)

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        d = np.abs(p_O) - 0.5 * np.asarray(self.size)
        outside = np.linalg.norm(np.maximum(d, 0.0), axis=-1)
        inside = np.minimum(np.max(d, axis=-1), 0.0)
        return outside + inside


@dataclass(frozen=True)
class Cylinder:
    """Cylinder of ``radius`` and full ``length`` [m] along z, centred at the frame origin."""

    radius: float
    length: float

    def __post_init__(self):
        object.__setattr__(self, "radius", _positive("Cylinder radius", self.radius))
        object.__setattr__(self, "length", _positive("Cylinder length", self.length))

    def to_drake(self):
        from pydrake.geometry import Cylinder as DrakeCylinder

        return DrakeCylinder(self.radius, self.length)

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        d_radial = np.hypot(p_O[..., 0], p_O[..., 1]) - self.radius
        d_axial = np.abs(p_O[..., 2]) - 0.5 * self.length
        outside = np.hypot(np.maximum(d_radial, 0.0), np.maximum(d_axial, 0.0))
        inside = np.minimum(np.maximum(d_radial, d_axial), 0.0)
        return outside + inside


@dataclass(frozen=True)
class Capsule:
    """Capsule: the points within ``radius`` of a segment of ``length`` [m] along z."""

    radius: float
    length: float

    def __post_init__(self):
        object.__setattr__(self, "radius", _positive("Capsule radius", self.radius))
        length = float(self.length)
        if not np.isfinite(length) or length < 0:
            raise SceneError(f"Capsule length must be >= 0 metres, got {length}")
        object.__setattr__(self, "length", length)

    def to_drake(self):
        from pydrake.geometry import Capsule as DrakeCapsule

        return DrakeCapsule(self.radius, self.length)

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        z = np.clip(p_O[..., 2], -0.5 * self.length, 0.5 * self.length)
        return np.sqrt(p_O[..., 0] ** 2 + p_O[..., 1] ** 2 + (p_O[..., 2] - z) ** 2) - self.radius


@dataclass(frozen=True)
class Ellipsoid:
    """Ellipsoid with semi-axes ``(a, b, c)`` [m] along x, y, z, centred at the frame origin.

    Robot collision geometry only (no closed-form signed distance; the sphere model covers it
    through a circumscribed polytope).
    """

    a: float
    b: float
    c: float

    def __post_init__(self):
        for name in "abc":
            object.__setattr__(self, name, _positive(f"Ellipsoid semi-axis {name}", getattr(self, name)))


@dataclass(frozen=True, eq=False)
class ConvexPolytope:
    """The convex hull of ``vertices_G (V, 3)`` [m], in the geometry frame G.

    Attributes:
        vertices: ``(V, 3)`` the hull's vertices (interior points dropped).
        normals: ``(F, 3)`` outward unit facet normals.
        offsets: ``(F,)``; a point p is inside iff ``normals @ p + offsets <= 0`` for every facet.

    Raises:
        UnsupportedGeometry: fewer than 4 points or all points in a plane (no volume).
    """

    vertices: np.ndarray
    normals: np.ndarray = None
    offsets: np.ndarray = None

    def __post_init__(self):
        from scipy.spatial import ConvexHull, QhullError

        points = np.asarray(self.vertices, dtype=float).reshape(-1, 3)
        if len(points) < 4 or not np.all(np.isfinite(points)):
            raise UnsupportedGeometry(f"a convex collision mesh needs at least 4 finite vertices, got {len(points)}")
        try:
            hull = ConvexHull(points)
        except QhullError as exc:
            raise UnsupportedGeometry(
                "the convex hull of a collision mesh has no volume (all vertices in a plane?); "
                "give the link a solid collision shape") from exc
        # coplanar triangles give repeated facet planes: keep one of each
        planes = np.unique(np.round(hull.equations, 12), axis=0)
        planes /= np.linalg.norm(planes[:, :3], axis=1, keepdims=True)
        object.__setattr__(self, "vertices", np.ascontiguousarray(points[hull.vertices]))
        object.__setattr__(self, "normals", np.ascontiguousarray(planes[:, :3]))
        object.__setattr__(self, "offsets", np.ascontiguousarray(planes[:, 3]))

    def halfspace_distance(self, p_G: np.ndarray) -> np.ndarray:
        """``max_k (n_k . p + d_k)`` ``(...)`` [m]: the exact signed distance for points inside,
        a lower bound of it (>= 0) for points outside."""
        return (np.asarray(p_G) @ self.normals.T + self.offsets).max(axis=-1)

    def fingerprint(self) -> bytes:
        """Bytes that identify the polytope (for cache keys)."""
        return np.ascontiguousarray(self.vertices).tobytes()


Shape = Sphere | Box | Cylinder | Capsule
RobotShape = Sphere | Box | Cylinder | Capsule | Ellipsoid | ConvexPolytope


def from_drake(shape) -> RobotShape:
    """Convert a ``pydrake.geometry`` shape to a drake_mh shape.

    ``Convex`` and ``Mesh`` become the :class:`ConvexPolytope` of their convex hull (scale
    included), which is what Drake's distance queries use for them.

    Raises:
        UnsupportedGeometry: half spaces, mesh files Drake cannot read ... (the message says
            which shape and what to use instead).
    """
    from pydrake.geometry import Box as DBox
    from pydrake.geometry import Capsule as DCapsule
    from pydrake.geometry import Convex as DConvex
    from pydrake.geometry import Cylinder as DCylinder
    from pydrake.geometry import Ellipsoid as DEllipsoid
    from pydrake.geometry import Mesh as DMesh
    from pydrake.geometry import Sphere as DSphere

    if isinstance(shape, DSphere):
        return Sphere(shape.radius())
    if isinstance(shape, DCapsule):
        return Capsule(shape.radius(), shape.length())
    if isinstance(shape, DCylinder):
        return Cylinder(shape.radius(), shape.length())
    if isinstance(shape, DBox):
        return Box((shape.width(), shape.depth(), shape.height()))
    if isinstance(shape, DEllipsoid):
        return Ellipsoid(shape.a(), shape.b(), shape.c())
    if isinstance(shape, (DConvex, DMesh)):
        try:
            hull = shape.GetConvexHull()
        except Exception as exc:  # Drake reads the file here (RuntimeError on formats it lacks)
            raise UnsupportedGeometry(
                f"cannot take the convex hull of collision mesh {shape.source().description()!r}: "
                f"{str(exc).strip().splitlines()[-1] if str(exc).strip() else exc}; "
                "convert it to .obj (drake_mh.load_robot does this for .stl/.dae)") from exc
        return ConvexPolytope(np.array([hull.vertex(i) for i in range(hull.num_vertices())]))
    raise UnsupportedGeometry(
        f"collision shape {type(shape).__name__} is not supported by the sphere model; "
        "describe the link's collision geometry with spheres, capsules, cylinders, boxes, "
        "ellipsoids or convex meshes")


def as_shape(shape) -> Shape:
    """Accept a drake_mh shape or a pydrake shape."""
    from pydrake.geometry import Shape as DrakeShape

    if isinstance(shape, (Sphere, Box, Cylinder, Capsule)):
        return shape
    if isinstance(shape, DrakeShape):
        return from_drake(shape)
    raise SceneError(f"expected a Sphere, Box, Cylinder or Capsule shape, got {shape!r}")
