"""Robots as Drake models: :class:`Robot`, :func:`load_robot` and what loading a model takes.

* :mod:`.robot` — :class:`Robot` (FK, Jacobians, dynamics, limits from the Drake plant),
  :func:`load_robot`, :func:`available_robots`, :func:`register_robot`;
* :mod:`.loading` — model formats (URDF, xacro, SDFormat, MJCF), mesh references rewritten,
  joints locked, drake_mh's own URDF attributes (:data:`~.loading.DRAKE_MH_NS`);
* :mod:`.packages` — ``package://`` resolution; :mod:`.meshes` — collision meshes as cached
  convex hulls; :mod:`.chain` — the arm chain to the end effector and the joints to lock;
  :mod:`.checks` — what a model must satisfy;
* :mod:`.dh` — DH tables to URDF (:func:`~.dh.dh_to_urdf`), with :mod:`.inertia`;
* :mod:`.examples` — the arms of ``example-robot-data`` by name.
"""

from drake_mh.robot.robot import URDF_DIR, Robot, available_robots, load_robot, register_robot
from drake_mh.robot.robot import _rebuild_robot, _reload_robot  # noqa: F401 - pickles made before robot/ was a package name them here

__all__ = ["Robot", "load_robot", "available_robots", "register_robot", "URDF_DIR"]
