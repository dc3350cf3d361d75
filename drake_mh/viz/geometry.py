"""Drawing a robot's geometry in Meshcat straight from its SceneGraph, at any configuration.

Rather than a ``MeshcatVisualizer`` system (one per diagram, publishing the diagram's own
context), the robot's geometry is read once from the SceneGraph model inspector and drawn as
a tree of Meshcat paths::

    <prefix>/<link>/<geometry>    shape, posed X_BG in its link frame B (fixed)
    <prefix>/<link>               pose X_WB of the link (set per configuration)

Setting a configuration only updates the link transforms, from ``robot.link_poses(q)``. A
*ghost* is the same geometry under another prefix with another colour (e.g. semi-transparent),
so any number of copies of the robot at different ``q`` share the one diagram.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["LinkGeometry", "RobotGeometry", "path_name", "rgba"]

DEFAULT_RGBA = (0.85, 0.85, 0.85, 1.0)
"""Colour of geometry without an illustration colour (e.g. collision geometry)."""


def path_name(name: str) -> str:
    """A Meshcat path component from any name: ``/`` and characters other than ``[A-Za-z0-9_.-]``
    become ``_`` (``::`` scoping included)."""
    return re.sub(r"[^A-Za-z0-9_.\-]", "_", str(name)) or "_"


def rgba(value, what: str = "rgba"):
    """A ``pydrake.geometry.Rgba`` from ``(r, g, b)`` or ``(r, g, b, a)`` in [0, 1] (or an Rgba).

    Raises:
        InvalidArgument: not 3 or 4 numbers in [0, 1].
    """
    from pydrake.geometry import Rgba

    if isinstance(value, Rgba):
        return value
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise InvalidArgument(f"{what} must be (r, g, b) or (r, g, b, a) in [0, 1], got {value!r}") from exc
    if arr.shape not in ((3,), (4,)) or not np.all((arr >= 0) & (arr <= 1)):
        raise InvalidArgument(f"{what} must be (r, g, b) or (r, g, b, a) in [0, 1], got {value!r}")
    return Rgba(*arr) if arr.size == 4 else Rgba(*arr, 1.0)


@dataclass(frozen=True)
class LinkGeometry:
    """One geometry of a link.

    Attributes:
        name: Meshcat path component of the geometry.
        shape: the ``pydrake.geometry.Shape``.
        X_BG: pose ``(4, 4)`` of the geometry in its link frame B.
        rgba: ``(4,)`` colour from the illustration properties (or :data:`DEFAULT_RGBA`).
    """

    name: str
    shape: object
    X_BG: np.ndarray
    rgba: tuple


class RobotGeometry:
    """The drawable geometry of a robot, grouped by link.

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        role: ``"illustration"`` (the URDF ``<visual>`` elements, default) or ``"proximity"``
            (``<collision>``: the shapes distances are computed on).

    Attributes:
        links: ``{link name: [LinkGeometry, ...]}``; geometry fixed to the world is under
            ``"world"``.
    """

    def __init__(self, robot, role: str = "illustration"):
        from pydrake.geometry import Role

        roles = {"illustration": Role.kIllustration, "proximity": Role.kProximity}
        if role not in roles:
            raise InvalidArgument(f"role must be one of {sorted(roles)}, got {role!r}")
        self.robot = robot
        self.role = role
        inspector = robot.scene_graph.model_inspector()
        plant = robot.plant
        self.links: dict[str, list[LinkGeometry]] = {}
        for gid in inspector.GetAllGeometryIds(roles[role]):
            frame_id = inspector.GetFrameId(gid)
            link = "world" if frame_id == inspector.world_frame_id() else plant.GetBodyFromFrameId(frame_id).name()
            colour = DEFAULT_RGBA
            props = inspector.GetIllustrationProperties(gid)
            if props is not None and props.HasProperty("phong", "diffuse"):
                c = props.GetProperty("phong", "diffuse")
                colour = (c.r(), c.g(), c.b(), c.a())
            items = self.links.setdefault(link, [])
            name = path_name(inspector.GetName(gid).split("::")[-1]) or f"g{len(items)}"
            if any(item.name == name for item in items):
                name = f"{name}_{len(items)}"
            items.append(LinkGeometry(name, inspector.GetShape(gid),
                                      inspector.GetPoseInFrame(gid).GetAsMatrix4(), colour))

    def link_paths(self, prefix: str) -> dict[str, str]:
        """``{link name: Meshcat path}`` under ``prefix``."""
        return {link: f"{prefix}/{path_name(link)}" for link in self.links}

    def draw(self, meshcat, prefix: str, colour=None, opacity: float | None = None) -> None:
        """Create the geometry under ``prefix`` (replacing what was there).

        Args:
            meshcat: the Meshcat instance.
            prefix: Meshcat path, e.g. ``"/drake_mh/robot"``.
            colour: one colour for every geometry (``(r, g, b[, a])``); default each
                geometry's own.
            opacity: alpha [0, 1] replacing the colours' alpha (ghosts), default unchanged.
        """
        from pydrake.geometry import Rgba
        from pydrake.math import RigidTransform

        fixed = None if colour is None else rgba(colour, "colour")
        meshcat.Delete(prefix)
        for link, items in self.links.items():
            link_path = f"{prefix}/{path_name(link)}"
            for item in items:
                c = fixed if fixed is not None else Rgba(*item.rgba)
                if opacity is not None:
                    c = Rgba(c.r(), c.g(), c.b(), float(opacity))
                path = f"{link_path}/{item.name}"
                meshcat.SetObject(path, item.shape, c)
                meshcat.SetTransform(path, RigidTransform(item.X_BG))

    def link_poses(self, q) -> dict[str, np.ndarray]:
        """Poses ``X_WB (4, 4)`` of the drawn links at ``q`` (world geometry: identity)."""
        poses = self.robot.link_poses(q)
        return {link: poses.get(link, np.eye(4)) for link in self.links}

    def set_configuration(self, meshcat, prefix: str, q, time_in_recording: float | None = None) -> None:
        """Pose the links drawn under ``prefix`` at ``q`` (optionally into the recording)."""
        from pydrake.math import RigidTransform

        for link, X_WB in self.link_poses(q).items():
            if time_in_recording is None:
                meshcat.SetTransform(f"{prefix}/{path_name(link)}", RigidTransform(X_WB))
            else:
                meshcat.SetTransform(f"{prefix}/{path_name(link)}", RigidTransform(X_WB), time_in_recording)
