"""``Obstacle``: a shape of the scene at a pose, possibly moving (what :class:`~drake_mh.scene.Scene`
holds and what scene files are read into)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import SceneError
from drake_mh.geometry import Box, Capsule, Cylinder, Mesh, PointCloud, Sphere

__all__ = ["Obstacle", "vector3", "rotation_rpy"]


@dataclass(frozen=True, eq=False)
class Obstacle:
    """An obstacle: a shape at pose ``X_WO`` moving with linear ``velocity_W`` [m/s]."""

    name: str
    shape: Sphere | Box | Cylinder | Capsule | Mesh | PointCloud
    X_WO: np.ndarray
    velocity_W: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def position(self) -> np.ndarray:
        """``p_WO (3,)`` [m]."""
        return self.X_WO[:3, 3].copy()


def vector3(value, what: str) -> np.ndarray:
    """``value`` as a new ``(3,)`` float array (a copy: an obstacle keeps it, the caller's array may
    change).

    Raises:
        SceneError: not 3 finite real numbers (``what`` names it).
    """
    try:  # numpy raises ValueError on ragged nested lists, in iscomplexobj too
        arr = None if isinstance(value, (str, bytes)) or np.iscomplexobj(value) \
            else np.array(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise SceneError(f"{what} must be 3 finite numbers, got {value!r}")
    return arr


def rotation_rpy(rpy) -> np.ndarray:
    """``R (3, 3)`` of roll-pitch-yaw angles ``rpy`` [rad] (Drake's ``RollPitchYaw``).

    Raises:
        SceneError: not 3 finite numbers.
    """
    from pydrake.math import RollPitchYaw

    return RollPitchYaw(vector3(rpy, "rpy [rad]")).ToRotationMatrix().matrix()
