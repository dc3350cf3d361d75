"""drake_mh's own scene YAML: what :meth:`drake_mh.scene.Scene.save` writes and ``load`` reads.

One mapping with a list of obstacles (docs/scene_files.md)::

    drake_mh_scene: 1                 # format version (written by save; optional when read)
    name: workcell                    # optional
    obstacles:
      - name: table                   # unique
        shape: box                    # sphere | box | cylinder | capsule | mesh | point_cloud
        size: [1.2, 0.8, 0.04]        # the shape's dimensions [m] (below)
        position: [0.5, 0.0, 0.38]    # p_WO [m], the shape's centre (its frame O) in the world
        rpy: [0.0, 0.0, 0.3]          # optional roll-pitch-yaw of O [rad] (Drake's RollPitchYaw) ...
        # quaternion: {w: 1.0, x: 0.0, y: 0.0, z: 0.0}  # ... or a unit quaternion, not both
        velocity: [0.0, 0.0, 0.0]     # optional linear velocity [m/s]

Dimensions by shape (the constructors' arguments): ``sphere``: ``radius``; ``box``: ``size``
(full sides x, y, z); ``cylinder`` and ``capsule``: ``radius``, ``length`` (along z);
``mesh``: ``file`` (path relative to the YAML file's folder, absolute, ``file://`` or
``package://``) and ``scale`` (one number or three; default 1); ``point_cloud``: ``radius``
and either ``file`` (.ply, .pcd, .xyz, .npy; optional ``scale``) or ``points`` (a list of
``[x, y, z]``). Unknown keys are refused (a typo must not pass silently).

Saving is exact to float precision: numbers are written with Python's shortest round-trip
``repr``, the orientation as ``rpy`` (the rotation rebuilt from it differs from the scene's by
about 1e-16), a point cloud's points beside the YAML file as ``<stem>.<obstacle>.npy``
(float64, so bit for bit) and a mesh by its file (relative when inside the YAML file's folder).
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import numpy as np

from drake_mh.errors import SceneFileError
from drake_mh.scene.files.common import SceneFile, SceneFileBuilder, pose

__all__ = ["read_native", "write_native", "VERSION", "SHAPE_KEYS"]

VERSION = 1
"""The format version :func:`write_native` writes and :func:`read_native` reads."""

SHAPE_KEYS = {
    "sphere": (("radius",), ()),
    "box": (("size",), ()),
    "cylinder": (("radius", "length"), ()),
    "capsule": (("radius", "length"), ()),
    "mesh": (("file",), ("scale",)),
    "point_cloud": (("radius",), ("file", "points", "scale")),
}
"""``{shape: (required keys, optional keys)}`` besides ``name``, ``shape`` and the pose keys."""

POSE_KEYS = ("position", "rpy", "quaternion", "velocity")


def read_native(path: Path, data, packages=None) -> SceneFile:
    """The :class:`~drake_mh.scene.files.common.SceneFile` of drake_mh scene YAML ``data`` read
    from ``path`` (module docstring).

    Raises:
        SceneFileError: another version, a missing or unknown key, a bad number, shape or pose,
            a duplicate name, a mesh or cloud file that cannot be read (naming the obstacle).
    """
    from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere

    b = SceneFileBuilder(path, "drake_mh")
    unknown = sorted(set(data) - {"drake_mh_scene", "name", "obstacles"})
    if unknown:
        raise b.error(f"unknown top-level key(s) {unknown}; expected drake_mh_scene, name, obstacles")
    version = data.get("drake_mh_scene", VERSION)
    if version != VERSION:
        raise b.error(f"drake_mh_scene: {version!r} is not a version this drake_mh reads (it reads {VERSION})")
    obstacles = data.get("obstacles")
    if obstacles is None:
        obstacles = []
    if not isinstance(obstacles, list):
        raise b.error(f"obstacles must be a list of mappings (one per obstacle), got {type(obstacles).__name__}")
    for k, item in enumerate(obstacles):
        entry = f"obstacle {k + 1}"
        if not isinstance(item, dict):
            raise b.error(f"each obstacle is a mapping (name, shape, its dimensions, position ...), got {item!r}",
                          entry)
        if isinstance(item.get("name"), str):
            entry += f" ({item['name']!r})"
        kind = item.get("shape")
        if kind not in SHAPE_KEYS:
            raise b.error(f"shape must be one of {', '.join(SHAPE_KEYS)}, got {kind!r}", entry)
        required, optional = SHAPE_KEYS[kind]
        missing = [key for key in ("name", "position", *required) if key not in item]
        if missing:
            raise b.error(f"a {kind} needs {', '.join(missing)}", entry)
        extra = sorted(set(item) - {"name", "shape", *POSE_KEYS, *required, *optional})
        if extra:
            raise b.error(f"unknown key(s) {extra} for a {kind}; it takes name, shape, "
                          f"{', '.join(required + optional)}, {', '.join(POSE_KEYS)}", entry)
        if kind == "sphere":
            shape = b.shape(Sphere, b.number(item["radius"], "radius [m]", entry), entry=entry)
        elif kind == "box":
            shape = b.shape(Box, b.numbers(item["size"], 3, "size [m] (x, y, z)", entry), entry=entry)
        elif kind in ("cylinder", "capsule"):
            shape = b.shape(Cylinder if kind == "cylinder" else Capsule, b.number(item["radius"], "radius [m]", entry),
                            b.number(item["length"], "length [m]", entry), entry=entry)
        elif kind == "mesh":
            shape = b.mesh(item["file"], item.get("scale", 1.0), entry, packages)
        else:
            if ("file" in item) == ("points" in item):
                raise b.error("a point_cloud needs either file or points (not both)", entry)
            if "scale" in item and "file" not in item:
                raise b.error("scale applies to a point_cloud file; give points in metres", entry)
            shape = b.cloud(item.get("points"), item.get("file"), item["radius"], item.get("scale", 1.0), entry,
                            packages)
        X = pose(_orientation(b, item, entry), b.numbers(item["position"], 3, "position [m]", entry))
        velocity = b.numbers(item["velocity"], 3, "velocity [m/s]", entry) if "velocity" in item else None
        b.add(item["name"], shape, X, entry, velocity)
    name = data.get("name", "")
    return b.result(name if isinstance(name, str) else str(name))


def _orientation(b: SceneFileBuilder, item: dict, entry: str) -> np.ndarray | None:
    from pydrake.math import RollPitchYaw

    if "rpy" in item and "quaternion" in item:
        raise b.error("give the orientation once: rpy or quaternion, not both", entry)
    if "rpy" in item:
        return RollPitchYaw(b.numbers(item["rpy"], 3, "rpy [rad]", entry)).ToRotationMatrix().matrix()
    if "quaternion" in item:
        q = item["quaternion"]
        if not isinstance(q, dict) or sorted(q) != ["w", "x", "y", "z"]:
            raise b.error(f"quaternion must be a mapping {{w: ..., x: ..., y: ..., z: ...}}, got {q!r}", entry)
        return b.rotation(q["w"], q["x"], q["y"], q["z"], entry, "w, x, y, z")
    return None


# --- writing -------------------------------------------------------------------------------------


def _floats(values) -> list:
    return [float(v) + 0.0 for v in np.asarray(values, dtype=float).reshape(-1)]  # + 0.0: no -0.0


def _file_name(path: Path, folder: Path) -> str:
    """``path`` relative to ``folder`` when inside it, else absolute."""
    try:
        return Path(path).resolve().relative_to(folder).as_posix()
    except ValueError:
        return str(Path(path).resolve())


def write_native(path, obstacles, name: str = "") -> list[Path]:
    """Write ``obstacles`` (:class:`~drake_mh.scene.Obstacle` s) as drake_mh scene YAML at
    ``path`` (module docstring), and each point cloud's points beside it.

    Returns:
        The files written (the YAML file first).

    Raises:
        SceneFileError: ``path`` does not end in ``.yaml`` / ``.yml``, its folder does not exist,
            or an obstacle's shape has no entry in the format.
    """
    import yaml
    from pydrake.math import RollPitchYaw, RotationMatrix

    from drake_mh._support.cache import atomic_write_bytes
    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.geometry.mesh import Mesh
    from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere

    path = Path(os.fspath(path)).expanduser()
    if path.suffix.lower() not in (".yaml", ".yml"):
        raise SceneFileError(path, "save writes drake_mh scene YAML: give a path ending in .yaml or .yml")
    folder = path.parent.resolve()
    if not folder.is_dir():
        raise SceneFileError(path, f"its folder {folder} does not exist; create it first")
    entries, clouds, used = [], [], set()
    for obstacle in obstacles:
        shape = obstacle.shape
        entry = {"name": obstacle.name}
        if isinstance(shape, Sphere):
            entry.update(shape="sphere", radius=float(shape.radius))
        elif isinstance(shape, Box):
            entry.update(shape="box", size=_floats(shape.size))
        elif isinstance(shape, (Cylinder, Capsule)):
            entry.update(shape=type(shape).__name__.lower(), radius=float(shape.radius), length=float(shape.length))
        elif isinstance(shape, Mesh):
            scale = _floats(shape.scale)
            entry.update(shape="mesh", file=_file_name(shape.path, folder),
                         scale=scale[0] if len(set(scale)) == 1 else scale)
        elif isinstance(shape, PointCloud):
            stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", obstacle.name).strip("._") or "cloud"
            side = folder / f"{path.stem}.{stem}.npy"
            k = 1
            while side.name in used:
                k += 1
                side = folder / f"{path.stem}.{stem}_{k}.npy"
            used.add(side.name)
            clouds.append((side, shape.points))
            entry.update(shape="point_cloud", file=side.name, radius=float(shape.radius))
        else:
            raise SceneFileError(path, f"obstacle {obstacle.name!r}: its shape {type(shape).__name__} has no entry "
                                       "in drake_mh scene YAML")
        entry["position"] = _floats(obstacle.X_WO[:3, 3])
        entry["rpy"] = _floats(RollPitchYaw(RotationMatrix(obstacle.X_WO[:3, :3])).vector())
        if np.any(obstacle.velocity_W != 0):
            entry["velocity"] = _floats(obstacle.velocity_W)
        entries.append(entry)
    document = {"drake_mh_scene": VERSION, **({"name": name} if name else {}), "obstacles": entries}
    text = ("# drake_mh scene (docs/scene_files.md): lengths [m], angles [rad], velocities [m/s]\n"
            + yaml.safe_dump(document, sort_keys=False, default_flow_style=None, width=120))
    written = []
    for side, points in clouds:
        buffer = io.BytesIO()
        np.save(buffer, np.ascontiguousarray(points, dtype=np.float64), allow_pickle=False)
        atomic_write_bytes(side, buffer.getvalue())
        written.append(side)
    atomic_write_bytes(path, text.encode())
    return [path, *written]
