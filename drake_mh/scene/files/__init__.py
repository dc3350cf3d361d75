"""Scene files: the obstacles of a cell read from the files it comes in, and drake_mh's own YAML.

:func:`read_scene` reads any of :data:`SCENE_FORMATS` into a :class:`SceneFile` (obstacles with
their poses, no robot involved); :func:`add_to_scene` puts them into a
:class:`~drake_mh.scene.Scene` all or nothing; :func:`write_scene` writes drake_mh scene YAML.
:meth:`Scene.from_file <drake_mh.scene.Scene.from_file>`, :meth:`Scene.load
<drake_mh.scene.Scene.load>` and :meth:`Scene.save <drake_mh.scene.Scene.save>` are the usual
way in (docs/scene_files.md).

Readers, one per family: :mod:`.native` (drake_mh YAML), :mod:`.drake_files` (SDFormat, URDF,
model directives, parsed by Drake), :mod:`.moveit` (``.scene`` text, planning-scene YAML as
MotionBenchMaker and robowflex write it), :mod:`.curobo` (cuRobo world YAML).

Every problem in a file raises :class:`~drake_mh.errors.SceneFileError` naming the file, the
entry (an obstacle's name or a line number) and what is expected; a missing file raises
:class:`~drake_mh.errors.SceneFileNotFound`.
"""

from __future__ import annotations

import os
from pathlib import Path

from drake_mh.errors import DrakeMhError, SceneFileError, SceneFileNotFound
from drake_mh.scene.files.common import SceneFile, read_text, read_yaml
from drake_mh.scene.files.curobo import CUROBO_KEYS

__all__ = ["read_scene", "write_scene", "add_to_scene", "detect_format", "SceneFile", "SCENE_FORMATS"]

SCENE_FORMATS = {
    "drake_mh": "drake_mh scene YAML (.yaml, .yml with 'obstacles:'), what Scene.save writes",
    "sdformat": "SDFormat world or models (.sdf, .world), parsed by Drake",
    "urdf": "URDF of static bodies (.urdf), parsed by Drake",
    "directives": "Drake model directives (.dmd.yaml), processed by Drake",
    "moveit_scene": "MoveIt .scene text file",
    "planning_scene": "MoveIt planning scene YAML, as MotionBenchMaker and robowflex write it ('world: "
                      "collision_objects:')",
    "curobo": "cuRobo world YAML ('cuboid:', 'sphere:', 'capsule:', 'cylinder:', 'mesh:')",
}
"""``{format: one line}`` of what :func:`read_scene` reads."""

_YAML_FORMATS = ("drake_mh", "directives", "planning_scene", "curobo")


def _yaml_format(path: Path, data) -> str:
    """The format of a YAML document by its top-level keys."""
    if not isinstance(data, dict) or not data:
        raise SceneFileError(path, "an empty or non-mapping YAML document; a scene file is a mapping "
                                   f"(formats: {', '.join(SCENE_FORMATS)})")
    keys = set(data)
    if "directives" in keys:
        return "directives"
    if keys & {"obstacles", "drake_mh_scene"}:
        return "drake_mh"
    if keys & {"world", "collision_objects"}:
        return "planning_scene"
    if keys <= set(CUROBO_KEYS) | {"blox"}:
        return "curobo"
    raise SceneFileError(path, f"cannot tell the format from its top-level keys {sorted(map(str, keys))}: drake_mh "
                               "scene YAML has 'obstacles', a planning scene 'world', cuRobo's world "
                               f"{', '.join(CUROBO_KEYS)}, model directives 'directives'; or pass format=")


def detect_format(path) -> str:
    """The format (a key of :data:`SCENE_FORMATS`) of the file at ``path``: by its suffix, and
    for ``.yaml`` / ``.yml`` (and ``.xml``) by what it holds.

    Raises:
        SceneFileNotFound: no such file.
        SceneFileError: a suffix or content of none of the formats.
    """
    return _detect(_checked(path))[0]


def _checked(path) -> Path:
    if not isinstance(path, (str, os.PathLike)) or not str(path):
        raise SceneFileError(repr(path), "expected the path of a scene file (str or pathlib.Path)")
    path = Path(path).expanduser()
    if not path.is_file():
        raise SceneFileNotFound(path, "no such file; give the path of an existing scene file")
    return path


def _detect(path: Path) -> tuple[str, object]:
    """``(format, YAML document or None)``."""
    name = path.name.lower()
    if name.endswith((".dmd.yaml", ".dmd.yml")):
        return "directives", None
    suffix = path.suffix.lower()
    if suffix in (".sdf", ".world"):
        return "sdformat", None
    if suffix == ".urdf":
        return "urdf", None
    if suffix == ".scene":
        return "moveit_scene", None
    if suffix in (".yaml", ".yml"):
        data = read_yaml(path)
        return _yaml_format(path, data), data
    if suffix == ".xml":
        head = read_text(path)[:4000]
        for root, fmt in (("<sdf", "sdformat"), ("<robot", "urdf")):
            if root in head:
                return fmt, None
    raise SceneFileError(path, f"unknown scene file suffix {suffix or '(none)'!r}: drake_mh reads .yaml/.yml (drake_mh, "
                               "planning scene, cuRobo), .dmd.yaml, .sdf/.world, .urdf, .xml (SDFormat, URDF) and "
                               ".scene; or pass format=")


def read_scene(path, format: str | None = None, packages=None, movable: str = "error") -> SceneFile:
    """Read the obstacles of a scene file.

    Args:
        path: the file.
        format: a key of :data:`SCENE_FORMATS` (default: :func:`detect_format`).
        packages: ``{"NAME": folder}`` for ``package://NAME/...`` file names (meshes, models),
            as :func:`drake_mh.load_robot` takes them.
        movable: SDFormat, URDF and directives: ``"error"`` (default) refuses bodies that can
            move; ``"default_pose"`` takes them where the file puts them
            (:mod:`.drake_files`).

    Returns:
        A :class:`SceneFile`.

    Raises:
        SceneFileNotFound: no such file.
        SceneFileError: an unknown format, or anything wrong in the file (named by its entry).
        InvalidArgument: a bad ``movable``.
    """
    path = _checked(path)
    if format is None:
        format, data = _detect(path)
    elif format not in SCENE_FORMATS:
        raise SceneFileError(path, f"unknown format {format!r}; formats: {', '.join(SCENE_FORMATS)}")
    elif format in _YAML_FORMATS and format != "directives":
        data = read_yaml(path)
        if not isinstance(data, dict):
            raise SceneFileError(path, f"a {format} file is a YAML mapping, got {type(data).__name__}")
    if format == "drake_mh":
        from drake_mh.scene.files.native import read_native

        return read_native(path, data, packages)
    if format == "planning_scene":
        from drake_mh.scene.files.moveit import read_planning_scene

        return read_planning_scene(data, path, packages=packages)
    if format == "moveit_scene":
        from drake_mh.scene.files.moveit import read_moveit_scene

        return read_moveit_scene(path)
    if format == "curobo":
        from drake_mh.scene.files.curobo import read_curobo

        return read_curobo(path, data, packages)
    from drake_mh.scene.files.drake_files import read_drake_file

    return read_drake_file(path, format, packages, movable)


def write_scene(path, obstacles, name: str = "") -> list[Path]:
    """Write obstacles as drake_mh scene YAML (:func:`drake_mh.scene.files.native.write_native`).

    Returns:
        The files written: the YAML file, then one ``.npy`` per point cloud.
    """
    from drake_mh.scene.files.native import write_native

    return write_native(path, obstacles, name)


def add_to_scene(scene, scene_file: SceneFile) -> list[str]:
    """Add a :class:`SceneFile`'s obstacles to ``scene``, all or nothing.

    Every pose is resolved first (:meth:`SceneFile.resolved`) and every name checked against
    the scene's; then the obstacles are added in order, and if one is refused the ones added
    before it are removed again: a failed call leaves the scene as it was.

    Returns:
        The names added.

    Raises:
        SceneFileError: a name the scene already has, a frame the robot cannot place, or an
            obstacle the scene refuses (naming it; the scene's error is the cause).
    """
    from pydrake.math import RollPitchYaw, RotationMatrix

    obstacles = scene_file.resolved(scene.robot)
    taken = [o.name for o in obstacles if o.name in scene.obstacles]
    if taken:
        raise SceneFileError(scene_file.path, f"the scene already has obstacle(s) named {taken}; remove them first "
                                              "(Scene.remove) or load into another scene")
    added: list[str] = []
    try:
        for obstacle in obstacles:
            rpy = RollPitchYaw(RotationMatrix(obstacle.X_WO[:3, :3])).vector()
            scene.add(obstacle.name, obstacle.shape, obstacle.X_WO[:3, 3], rpy, obstacle.velocity_W)
            added.append(obstacle.name)
    except BaseException as exc:
        for name in reversed(added):
            scene.remove(name)
        if isinstance(exc, DrakeMhError) and not isinstance(exc, SceneFileError):
            raise SceneFileError(scene_file.path, f"the scene refuses it: {exc}",
                                 f"obstacle {obstacle.name!r}") from exc
        raise
    return added
