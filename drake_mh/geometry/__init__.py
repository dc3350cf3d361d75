"""Shapes and the conservative sphere model of a robot's collision geometry.

* :mod:`.shapes` — :class:`Sphere`, :class:`Box`, :class:`Cylinder`, :class:`Capsule`,
  :class:`Ellipsoid`, :class:`ConvexPolytope` (obstacles and link geometry, read from Drake
  with :func:`~.shapes.from_drake`);
* :mod:`.spheres` — :class:`SphereModel`: spheres that cover every collision geometry of a
  robot, with a stated bound, cached on disk;
* :mod:`.sphere_cover` — the covering of one shape.
"""

from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere, as_shape, from_drake
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE, SphereModel

__all__ = ["Sphere", "Box", "Cylinder", "Capsule", "Ellipsoid", "ConvexPolytope", "as_shape", "from_drake",
           "SphereModel", "DEFAULT_TOLERANCE"]
