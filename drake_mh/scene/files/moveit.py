"""MoveIt's scene files: the ``.scene`` text format and planning scenes in YAML.

**``.scene`` text** (MoveIt's ``PlanningScene::loadGeometryFromStream``): the first line is the
scene's name; each object starts with ``* <name>``; ``.`` ends the file. Per object::

    * table                  object name (rest of the line)
    0.5 0 0.4                object pose: position   } only in the newer format, recognised as MoveIt
    0 0 0 1                  object pose: x y z w    } does: the line after the first '*' has spaces
    1                        number of shapes
    box                      shape: box | sphere | cylinder | cone | plane | mesh
    1.2 0.8 0.04             box: x y z; sphere: radius; cylinder: radius length;
                             mesh: V T, then V lines "x y z" and T lines "i j k" (0-based)
    0 0 0                    shape position                      } relative to the object pose
    0 0 0 1                  shape orientation, quaternion x y z w } (newer format)
    0.5 0.5 0.5 1            colour r g b a (ignored)
    0                        number of subframes, then per subframe: name, position, quaternion
                             (newer format; read and ignored)
    .

Lengths are metres; an object with one shape is one obstacle named as the object, one with
several shapes gives ``name_0``, ``name_1`` ... Cones and planes have no drake_mh shape and
are refused (say which line).

**Planning scene YAML** (``moveit_msgs/PlanningScene`` as MotionBenchMaker and robowflex
write it, or a bare ``PlanningSceneWorld`` with ``collision_objects``): each
``world.collision_objects`` entry has ``id``, ``header.frame_id``, an optional object ``pose``
(MoveIt >= 1.1.6; shape poses are relative to it), ``primitives`` + ``primitive_poses``
(``type`` ``box`` ``[x, y, z]`` / ``sphere`` ``[radius]`` / ``cylinder`` ``[height, radius]``,
MoveIt's order; or the numeric types 1, 2, 3) and ``meshes`` + ``mesh_poses`` (robowflex's
``resource`` file with ``dimensions`` as its scale, or ``vertices`` + ``triangles``).
Positions are ``[x, y, z]`` or ``{x, y, z}``, orientations ``[x, y, z, w]`` or ``{x, y, z, w}``.
Poses are in ``header.frame_id``: the world, or a robot frame welded to it
(:meth:`~drake_mh.scene.files.common.SceneFile.resolved`). ``robot_state.joint_state`` is kept
as :attr:`~drake_mh.scene.files.common.SceneFile.robot_state`. Refused: cones, planes, octomaps,
objects attached to the robot, and ``remove`` / ``move`` operations.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.scene.files.common import SceneFile, SceneFileBuilder, pose, read_text

__all__ = ["read_moveit_scene", "read_planning_scene"]

_SCENE_DIMENSIONS = {"box": 3, "sphere": 1, "cylinder": 2, "cone": 2, "plane": 4}


class _Tokens:
    """The whitespace-separated tokens of a ``.scene`` file with their line numbers."""

    def __init__(self, b: SceneFileBuilder, lines: list[str]):
        self.b = b
        self.items: list[tuple[str, str, int]] = []  # ("*", name, line) or ("tok", text, line)
        for number, line in enumerate(lines, start=2):
            text = line.strip()
            if text.startswith("*"):
                self.items.append(("*", text[1:].strip(), number))
            else:
                self.items += [("tok", token, number) for token in text.split()]
        self.i = 0

    def peek(self):
        return self.items[self.i] if self.i < len(self.items) else None

    def where(self) -> str:
        item = self.peek()
        return f"line {item[2]}" if item else "end of file"

    def word(self, what: str) -> str:
        item = self.peek()
        if item is None or item[0] != "tok":
            raise self.b.error(f"{what} expected, got {'the end of the file' if item is None else 'a new object'}",
                               self.where())
        self.i += 1
        return item[1]

    def numbers(self, count: int, what: str) -> np.ndarray:
        first = self.where()
        values = []
        for _ in range(count):
            where = self.where()
            token = self.word(what)
            try:
                values.append(float(token))
            except ValueError:
                raise self.b.error(f"{what}: {count} number{'s' if count > 1 else ''} expected, got {token!r}",
                                   where) from None
        out = np.array(values)
        if not np.all(np.isfinite(out)):
            raise self.b.error(f"{what}: finite numbers expected, got {values}", first)
        return out

    def count(self, what: str) -> int:
        where = self.where()
        token = self.word(what)
        if not token.isdigit():
            raise self.b.error(f"{what}: a whole number >= 0 expected, got {token!r}", where)
        return int(token)

    def pose(self, what: str) -> np.ndarray:
        p = self.numbers(3, f"{what} position x y z")
        where = self.where()
        x, y, z, w = self.numbers(4, f"{what} orientation quaternion x y z w")
        return pose(self.b.rotation(w, x, y, z, where, "x y z w"), p)


def read_moveit_scene(path: Path) -> SceneFile:
    """The obstacles of a MoveIt ``.scene`` text file (module docstring).

    Raises:
        SceneFileError: a malformed line (its number is in the message), a cone or plane, a
            duplicate object name.
    """
    from drake_mh.geometry.shapes import Box, Cylinder, Sphere

    b = SceneFileBuilder(path, "moveit_scene")
    lines = read_text(path).splitlines()
    if not lines or not lines[0].strip():
        raise b.error("a .scene file starts with the scene's name on its first line", "line 1")
    tokens = _Tokens(b, lines[1:])
    stars = [k for k, item in enumerate(tokens.items) if item[0] == "*"]
    newer = False
    if stars and stars[0] + 1 < len(tokens.items):
        line = tokens.items[stars[0] + 1][2]
        newer = " " in lines[line - 1].strip()  # an object pose line (MoveIt's own test)
    while True:
        item = tokens.peek()
        if item is None or item[:2] == ("tok", "."):
            break
        if item[0] != "*":
            raise b.error(f"'* <object name>' or '.' expected, got {item[1]!r}", f"line {item[2]}")
        tokens.i += 1
        name, start = item[1], item[2]
        X_WB = tokens.pose(f"object {name!r} pose") if newer else np.eye(4)
        n = tokens.count(f"object {name!r}: number of shapes")
        for k in range(n):
            where = tokens.where()
            kind = tokens.word(f"object {name!r}: shape type")
            entry = f"{where} (object {name!r})"
            if kind == "mesh":
                counts = (tokens.count("mesh: number of vertices"), tokens.count("mesh: number of triangles"))
                vertices = tokens.numbers(3 * counts[0], "mesh vertices x y z")
                faces = tokens.numbers(3 * counts[1], "mesh triangles i j k")
                shape = b.inline_mesh(vertices, faces, entry)
            elif kind in _SCENE_DIMENSIONS:
                dims = tokens.numbers(_SCENE_DIMENSIONS[kind], f"{kind} dimensions")
                if kind == "box":
                    shape = b.shape(Box, dims, entry=entry)
                elif kind == "sphere":
                    shape = b.shape(Sphere, dims[0], entry=entry)
                elif kind == "cylinder":
                    shape = b.shape(Cylinder, dims[0], dims[1], entry=entry)  # radius, length
                else:
                    raise b.error(f"a {kind} has no drake_mh obstacle shape; replace it with a "
                                  f"{'cylinder or a mesh' if kind == 'cone' else 'thin box'}", entry)
            else:
                raise b.error(f"unknown shape type {kind!r}; expected box, sphere, cylinder or mesh", entry)
            X_BS = tokens.pose(f"object {name!r} shape {k}")
            tokens.numbers(4, "colour r g b a")
            b.add(name if n == 1 else f"{name}_{k}", shape, X_WB @ X_BS, f"line {start} (object {name!r})")
        if newer:
            for _ in range(tokens.count(f"object {name!r}: number of subframes")):
                tokens.word("subframe name")
                tokens.pose("subframe")
    return b.result(lines[0].strip())


# --- planning scene YAML ----------------------------------------------------------------------

_PRIMITIVES = {1: "box", 2: "sphere", 3: "cylinder", 4: "cone"}
_OPERATIONS = {0: "add", 1: "remove", 2: "append", 3: "move"}


def _msg_pose(b: SceneFileBuilder, value, entry: str) -> np.ndarray:
    """A ``geometry_msgs/Pose`` (missing parts: zero, identity)."""
    if value is None:
        return np.eye(4)
    if not isinstance(value, dict):
        raise b.error(f"a pose is a mapping with position and orientation, got {value!r}", entry)
    position = value.get("position", [0.0, 0.0, 0.0])
    if isinstance(position, dict):
        position = [position.get(k) for k in "xyz"]
    orientation = value.get("orientation", [0.0, 0.0, 0.0, 1.0])
    if isinstance(orientation, dict):
        orientation = [orientation.get(k) for k in "xyzw"]
    x, y, z, w = b.numbers(orientation, 4, "orientation (x, y, z, w)", entry)
    return pose(b.rotation(w, x, y, z, entry, "x, y, z, w"), b.numbers(position, 3, "position (x, y, z)", entry))


def _pairs(b: SceneFileBuilder, obj: dict, shapes: str, poses: str, entry: str) -> list:
    items, at = obj.get(shapes) or [], obj.get(poses) or []
    if not isinstance(items, list) or not isinstance(at, list) or len(items) != len(at):
        raise b.error(f"{shapes} and {poses} must be lists of the same length (one pose per shape)", entry)
    return list(zip(items, at))


def _primitive(b: SceneFileBuilder, primitive, entry: str):
    from drake_mh.geometry.shapes import Box, Cylinder, Sphere

    if not isinstance(primitive, dict):
        raise b.error(f"a primitive is a mapping with type and dimensions, got {primitive!r}", entry)
    kind = primitive.get("type")
    kind = _PRIMITIVES.get(kind, kind) if not isinstance(kind, bool) else kind
    dims = primitive.get("dimensions")
    if kind == "box":
        return b.shape(Box, b.numbers(dims, 3, "box dimensions [x, y, z]", entry), entry=entry)
    if kind == "sphere":
        return b.shape(Sphere, b.numbers(dims, 1, "sphere dimensions [radius]", entry)[0], entry=entry)
    if kind == "cylinder":
        height, radius = b.numbers(dims, 2, "cylinder dimensions [height, radius]", entry)
        return b.shape(Cylinder, radius, height, entry=entry)
    if kind == "cone":
        raise b.error("a cone has no drake_mh obstacle shape; replace it with a cylinder or a mesh", entry)
    raise b.error(f"primitive type must be box, sphere or cylinder, got {kind!r}", entry)


def _mesh(b: SceneFileBuilder, mesh, entry: str, packages):
    if not isinstance(mesh, dict):
        raise b.error(f"a mesh is a mapping (resource and dimensions, or vertices and triangles), got {mesh!r}", entry)
    if "resource" in mesh:
        return b.mesh(mesh["resource"], mesh.get("dimensions", 1.0), entry, packages)
    vertices = [[v.get(k) for k in "xyz"] if isinstance(v, dict) else v for v in mesh.get("vertices") or []]
    faces = [t.get("vertex_indices") if isinstance(t, dict) else t for t in mesh.get("triangles") or []]
    return b.inline_mesh(vertices, faces, entry)


def read_planning_scene(data: dict, path, folder="", packages=None) -> SceneFile:
    """The obstacles of a planning scene (module docstring) read from YAML ``data``.

    Args:
        data: the YAML document (a mapping).
        path: the file, or the data's name (an archive member), for messages.
        folder: where relative mesh file names resolve (default ``path``'s folder; ``None``: none).
        packages: ``{name: folder}`` for ``package://`` mesh names.

    Raises:
        SceneFileError: a malformed or unsupported entry (named by its object id).
    """
    b = SceneFileBuilder(path, "planning_scene", folder)
    world = data.get("world", data) if isinstance(data, dict) else None
    if not isinstance(world, dict):
        raise b.error("a planning scene is a mapping with world: {collision_objects: [...]}")
    octomap = (world.get("octomap") or {}).get("octomap") or {}
    if octomap.get("data"):
        raise b.error("octomaps are not read; turn the map into a point cloud (.ply, .pcd) and add it as a PointCloud",
                      "world.octomap")
    objects = world.get("collision_objects") or []
    if not isinstance(objects, list):
        raise b.error("world.collision_objects must be a list", "world.collision_objects")
    for k, obj in enumerate(objects):
        entry = f"collision object {k + 1}"
        if not isinstance(obj, dict):
            raise b.error(f"a collision object is a mapping, got {obj!r}", entry)
        name = str(obj.get("id", ""))
        entry += f" ({name!r})"
        operation = obj.get("operation", "add")
        operation = _OPERATIONS.get(operation, operation) if not isinstance(operation, bool) else operation
        if operation not in ("add", "append"):
            raise b.error(f"operation {operation!r}: a scene file lists what is there (add); remove and move are not "
                          "read", entry)
        header = obj.get("header") or {}
        frame = str(header.get("frame_id", "") if isinstance(header, dict) else "")
        X_FB = _msg_pose(b, obj.get("pose"), entry)
        if obj.get("planes"):
            raise b.error("planes are not read; give the floor or wall as a thin box", entry)
        shapes = [(_primitive(b, s, entry), _msg_pose(b, p, entry))
                  for s, p in _pairs(b, obj, "primitives", "primitive_poses", entry)]
        shapes += [(_mesh(b, m, entry, packages), _msg_pose(b, p, entry))
                   for m, p in _pairs(b, obj, "meshes", "mesh_poses", entry)]
        if not shapes:
            raise b.error("it has no primitives or meshes", entry)
        for j, (shape, X_BS) in enumerate(shapes):
            b.add(name if len(shapes) == 1 else f"{name}_{j}", shape, X_FB @ X_BS, entry, frame=frame)
    state = data.get("robot_state") or {} if isinstance(data, dict) else {}
    if state.get("attached_collision_objects"):
        raise b.error("objects attached to the robot are part of the robot, not obstacles; add them to the robot "
                      "model instead", "robot_state.attached_collision_objects")
    joints = state.get("joint_state") or {}
    names, positions = joints.get("name") or [], joints.get("position") or []
    if len(names) != len(positions):
        raise b.error(f"{len(names)} joint names but {len(positions)} positions", "robot_state.joint_state")
    robot_state = {str(n): b.number(p, f"joint {n!r} position", "robot_state.joint_state")
                   for n, p in zip(names, positions)}
    return b.result(str(data.get("name", "")) if isinstance(data, dict) else "", robot_state)
