"""Shapes and the conservative sphere model of a robot's collision geometry.

* :mod:`.shapes` — :class:`Sphere`, :class:`Box`, :class:`Cylinder`, :class:`Capsule`,
  :class:`Ellipsoid`, :class:`ConvexPolytope` (obstacles and link geometry, read from Drake
  with :func:`~.shapes.from_drake`);
* :mod:`.spheres` — :class:`SphereModel`: spheres that cover every collision geometry of a
  robot, with a stated bound, cached on disk;
* :mod:`.sphere_cover` — the covering of one shape;
* :mod:`.mesh` — :class:`Mesh`: a triangle-mesh obstacle read from a file;
* :mod:`.cloud` — :class:`PointCloud`: a point-cloud obstacle (arrays or files,
  :mod:`.cloud_files`), cropping, down-sampling, the robot's own points removed.
"""

from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere, as_shape, from_drake
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE, SphereModel
from drake_mh.geometry.mesh import Mesh
from drake_mh.geometry.cloud import PointCloud

__all__ = ["Sphere", "Box", "Cylinder", "Capsule", "Ellipsoid", "ConvexPolytope", "as_shape", "from_drake",
           "SphereModel", "DEFAULT_TOLERANCE", "Mesh", "PointCloud"]
