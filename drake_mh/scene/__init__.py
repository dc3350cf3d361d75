"""The collision layer: obstacles around a robot and every query against them.

* :mod:`drake_mh.scene.scene` — :class:`Scene`: obstacles (pose, velocity), exact distances
  (Drake, refined where Drake is optimistic) and the sphere model's batched clearance.
* :mod:`drake_mh.scene.penetration` — lower bounds of the exact distance where a sphere of the
  model penetrates an obstacle.
* :mod:`drake_mh.scene.exact` — the exact distances behind ``Scene.distances`` / ``min_distance``
  (compiled kernels :mod:`~drake_mh.scene.kernels.exact`, certified GJK :mod:`~drake_mh.scene.kernels.gjk`).
* :mod:`drake_mh.scene.segment_distance` — exact capsule vs box/cylinder/capsule distances (the
  pairs where Drake's GJK is optimistic).
* :mod:`drake_mh.scene.files` — scene files (SDFormat, URDF, model directives, MoveIt, cuRobo,
  drake_mh's own YAML) behind ``Scene.from_file``, ``Scene.load`` and ``Scene.save``.
"""

from drake_mh.scene.scene import Box, Capsule, Cylinder, DistancePair, Mesh, Obstacle, PointCloud, Scene, Sphere

__all__ = ["Scene", "Obstacle", "DistancePair", "Sphere", "Box", "Cylinder", "Capsule", "Mesh", "PointCloud"]
