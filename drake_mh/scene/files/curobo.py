"""cuRobo's world configuration YAML (``curobo.geom.types.WorldConfig.from_dict``).

One mapping per obstacle type, each ``{name: fields}``; every pose is
``[x, y, z, qw, qx, qy, qz]`` (scalar first) in the frame cuRobo plans in, the robot's base,
read here as the world (a drake_mh robot's base sits at the world origin unless its model welds
it elsewhere)::

    cuboid:   {table: {dims: [x, y, z], pose: [...]}}           full side lengths [m]
    sphere:   {ball: {radius: r, pose: [...]}}                  (or the old position: [x, y, z])
    cylinder: {post: {radius: r, height: h, pose: [...]}}       axis along z
    capsule:  {rail: {radius: r, base: [x, y, z], tip: [x, y, z], pose: [...]}}
    mesh:     {bin: {file_path: bin.obj, scale: [sx, sy, sz], pose: [...]}}
              (or vertices: [[x, y, z], ...] and faces: [[i, j, k], ...])

A capsule is the segment from ``base`` to ``tip`` (in the pose's frame) swept by ``radius``,
as its fields say (cuRobo's own mesh conversion centres it on the pose instead, which agrees
when ``base = -tip``). A relative ``file_path`` resolves against the YAML file's folder
(cuRobo resolves it against its own assets folder). ``color``, ``texture``, ``texture_id``
and ``material`` are looks and ignored; ``scale`` on shapes other than meshes is ignored, as
cuRobo does (with a warning). ``blox`` (nvblox maps) is refused.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from drake_mh.scene.files.common import SceneFile, SceneFileBuilder, pose

__all__ = ["read_curobo", "CUROBO_KEYS"]

logger = logging.getLogger(__name__)

CUROBO_KEYS = {
    "cuboid": ("dims",),
    "sphere": ("radius",),
    "cylinder": ("radius", "height"),
    "capsule": ("radius", "base", "tip"),
    "mesh": (),
}
"""``{obstacle type: its required fields}`` besides ``pose``."""

_LOOKS = ("color", "texture", "texture_id", "material", "scale")
_OPTIONAL = {"sphere": ("position",), "mesh": ("file_path", "vertices", "faces")}


def _pose7(b: SceneFileBuilder, value, entry: str) -> np.ndarray:
    x, y, z, qw, qx, qy, qz = b.numbers(value, 7, "pose [x, y, z, qw, qx, qy, qz]", entry)
    return pose(b.rotation(qw, qx, qy, qz, entry, "qw, qx, qy, qz"), [x, y, z])


def _capsule(b: SceneFileBuilder, item: dict, entry: str) -> tuple:
    """``(Capsule, X_PO)``: the capsule from ``base`` to ``tip`` in its pose's frame P."""
    from pydrake.math import RotationMatrix

    from drake_mh.geometry.shapes import Capsule

    base = b.numbers(item["base"], 3, "base [x, y, z]", entry)
    tip = b.numbers(item["tip"], 3, "tip [x, y, z]", entry)
    axis = tip - base
    length = float(np.linalg.norm(axis))
    along_z = length == 0 or abs(abs(axis[2]) - length) <= 1e-12 * length  # a capsule is symmetric
    R = np.eye(3) if along_z else RotationMatrix.MakeFromOneVector(axis, 2).matrix()
    return b.shape(Capsule, b.number(item["radius"], "radius [m]", entry), length, entry=entry), \
        pose(R, 0.5 * (base + tip))


def read_curobo(path: Path, data: dict, packages=None) -> SceneFile:
    """The obstacles of cuRobo world YAML ``data`` read from ``path`` (module docstring).

    Raises:
        SceneFileError: an unknown obstacle type or field, a missing field, a bad number or
            pose, ``blox``, a mesh file that cannot be read.
    """
    from drake_mh.geometry.shapes import Box, Cylinder, Sphere

    b = SceneFileBuilder(path, "curobo")
    for kind, group in data.items():
        if kind == "blox":
            raise b.error("nvblox maps are not read; export the map's mesh (mesh: {file_path: ...}) or its points "
                          "(a PointCloud)", "blox")
        if kind not in CUROBO_KEYS:
            raise b.error(f"unknown obstacle type {kind!r}; cuRobo's are {', '.join(CUROBO_KEYS)}", str(kind))
        if group is None:
            continue
        if not isinstance(group, dict):
            raise b.error(f"{kind} must map obstacle names to their fields, got {group!r}", kind)
        for name, item in group.items():
            entry = f"{kind} {name!r}"
            if not isinstance(item, dict):
                raise b.error(f"fields expected (a mapping), got {item!r}", entry)
            required = CUROBO_KEYS[kind]
            extra = sorted(set(item) - {"pose", *required, *_OPTIONAL.get(kind, ()), *_LOOKS})
            if extra:
                fields = ", ".join(("pose", *required, *_OPTIONAL.get(kind, ())))
                raise b.error(f"unknown field(s) {extra}; a {kind} has {fields} (and looks: {', '.join(_LOOKS)})",
                              entry)
            missing = [key for key in required if key not in item]
            if "pose" not in item and not (kind == "sphere" and "position" in item):
                missing.insert(0, "pose")
            if missing:
                raise b.error(f"a {kind} needs {', '.join(missing)}", entry)
            if kind == "sphere" and "pose" not in item:
                X = pose(p=b.numbers(item["position"], 3, "position [x, y, z]", entry))
            else:
                X = _pose7(b, item["pose"], entry)
            if kind != "mesh" and item.get("scale") is not None:
                logger.warning("%s, %s: scale is ignored on a %s (as cuRobo does)", path, entry, kind)
            if kind == "cuboid":
                shape = b.shape(Box, b.numbers(item["dims"], 3, "dims [x, y, z]", entry), entry=entry)
            elif kind == "sphere":
                shape = b.shape(Sphere, b.number(item["radius"], "radius [m]", entry), entry=entry)
            elif kind == "cylinder":
                shape = b.shape(Cylinder, b.number(item["radius"], "radius [m]", entry),
                                b.number(item["height"], "height [m]", entry), entry=entry)
            elif kind == "capsule":
                shape, X_PO = _capsule(b, item, entry)
                X = X @ X_PO
            else:
                shape = _mesh(b, item, entry, packages)
            b.add(str(name), shape, X, entry)
    return b.result()


def _mesh(b: SceneFileBuilder, item: dict, entry: str, packages):
    scale = item.get("scale")
    if item.get("file_path") is not None:
        if item.get("vertices") is not None:
            raise b.error("give file_path or vertices and faces, not both", entry)
        return b.mesh(item["file_path"], 1.0 if scale is None else scale, entry, packages)
    if item.get("vertices") is None or item.get("faces") is None:
        raise b.error("a mesh needs file_path, or vertices and faces", entry)
    try:
        vertices = np.asarray(item["vertices"], dtype=float).reshape(-1, 3)
    except (TypeError, ValueError):
        raise b.error("vertices must be a list of [x, y, z] [m]", entry) from None
    if scale is not None:
        vertices = vertices * b.numbers(np.broadcast_to(scale, 3) if np.ndim(scale) == 0 else scale, 3,
                                        "scale [sx, sy, sz]", entry)
    return b.inline_mesh(vertices, item["faces"], entry)
