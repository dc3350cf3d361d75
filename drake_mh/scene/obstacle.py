"""``Obstacle``: a shape of the scene at a pose, possibly moving (what :class:`~drake_mh.scene.Scene`
holds and what scene files are read into)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.geometry import Box, Capsule, Cylinder, Mesh, PointCloud, Sphere

__all__ = ["Obstacle"]


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
