"""Cartesian paths (framework paper §3.3) and IK along them with continuity.

* :func:`trapezoidal_path` — straight segments through start / intermediate / end stop
  points, a trapezoidal speed profile per segment, ``N`` points (Table 3: 50);
* :func:`ik_along_path` — position IK at every point with any IK method, warm-started from the
  previous point and with a joint-displacement penalty; reports the largest joint step.

See ``docs/trajectories.md``.
"""

from drake_mh.paths.cartesian import TABLE3_POINTS, CartesianPath, TrapezoidalProfile, trapezoidal_path
from drake_mh.paths.ik_path import JointPath, ik_along_path, joint_steps

__all__ = ["trapezoidal_path", "CartesianPath", "TrapezoidalProfile", "TABLE3_POINTS", "ik_along_path", "joint_steps",
           "JointPath"]
