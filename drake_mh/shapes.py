"""Primitive shapes: obstacles and the robot's collision geometry.

Each shape is a frozen dataclass expressed in its own frame O (centred at the origin; the axis
of cylinders and capsules is z, as in Drake) with

* ``to_drake()``: the matching ``pydrake.geometry`` shape (for exact distances in SceneGraph);
* ``signed_distance(p_O)``: vectorized signed distance ``(...)`` [m] from points ``p_O (..., 3)``
  expressed in O — positive outside, negative inside (minus the depth to the surface).

These closed forms are used by the batched distance queries of the sphere model; the exact
robot-obstacle distances always come from Drake.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import SceneError, UnsupportedGeometry


def _positive(name: str, value: float) -> float:
    value = float(value)
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


@dataclass(frozen=True)
class Box:
    """Box of full side lengths ``size = (x, y, z)`` [m] centred at the frame origin."""

    size: tuple

    def __post_init__(self):
        size = np.asarray(self.size, dtype=float).reshape(-1)
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


Shape = Sphere | Box | Cylinder | Capsule


def from_drake(shape) -> Shape:
    """Convert a ``pydrake.geometry`` shape to a drake_mh shape.

    Raises:
        UnsupportedGeometry: meshes, ellipsoids, half spaces ... (model the link with
            spheres, capsules, cylinders or boxes instead).
    """
    from pydrake.geometry import Box as DBox
    from pydrake.geometry import Capsule as DCapsule
    from pydrake.geometry import Cylinder as DCylinder
    from pydrake.geometry import Sphere as DSphere

    if isinstance(shape, DSphere):
        return Sphere(shape.radius())
    if isinstance(shape, DCapsule):
        return Capsule(shape.radius(), shape.length())
    if isinstance(shape, DCylinder):
        return Cylinder(shape.radius(), shape.length())
    if isinstance(shape, DBox):
        return Box((shape.width(), shape.depth(), shape.height()))
    raise UnsupportedGeometry(
        f"collision shape {type(shape).__name__} is not supported by the sphere model; "
        "describe the link's collision geometry with spheres, capsules, cylinders or boxes")


def as_shape(shape) -> Shape:
    """Accept a drake_mh shape or a pydrake shape."""
    from pydrake.geometry import Shape as DrakeShape

    if isinstance(shape, (Sphere, Box, Cylinder, Capsule)):
        return shape
    if isinstance(shape, DrakeShape):
        return from_drake(shape)
    raise SceneError(f"expected a Sphere, Box, Cylinder or Capsule shape, got {shape!r}")
