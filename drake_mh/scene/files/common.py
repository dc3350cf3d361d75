"""What every scene-file reader shares: the parsed file, checked numbers, poses and errors.

A reader collects the file's obstacles with a :class:`SceneFileBuilder`, which checks each
entry as it comes (numbers, rotations, shapes, mesh and cloud files) and raises a
:class:`~drake_mh.errors.SceneFileError` naming the file, the entry and what is expected. The
result is a :class:`SceneFile`: obstacles with their poses, not yet in any scene.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_mh.errors import DrakeMhError, SceneFileError
from drake_mh.scene.obstacle import Obstacle

__all__ = ["SceneFile", "SceneFileBuilder", "WORLD_FRAMES", "quaternion_matrix", "pose", "read_yaml", "read_text"]

WORLD_FRAMES = ("", "world", "/world")
"""Frame names read as the world frame (a planning scene's ``header.frame_id``)."""

QUATERNION_TOLERANCE = 1e-2
"""A quaternion whose norm is within this of 1 is normalized; further off, it is refused (a
quaternion of norm 2 is more likely numbers in the wrong order than a rotation)."""


def quaternion_matrix(w: float, x: float, y: float, z: float) -> np.ndarray | None:
    """``R (3, 3)`` of the quaternion ``w + xi + yj + zk`` after normalizing it, or ``None`` when
    its norm is not within :data:`QUATERNION_TOLERANCE` of 1."""
    q = np.array([w, x, y, z], dtype=float)
    n = float(np.linalg.norm(q))
    if not np.isfinite(n) or abs(n - 1.0) > QUATERNION_TOLERANCE:
        return None
    w, x, y, z = q / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose(R: np.ndarray | None = None, p=None) -> np.ndarray:
    """``X (4, 4)`` from a rotation and a translation (identity where ``None``)."""
    X = np.eye(4)
    if R is not None:
        X[:3, :3] = R
    if p is not None:
        X[:3, 3] = p
    return X


@dataclass(frozen=True)
class SceneFile:
    """The obstacles a scene file describes, before they enter a :class:`~drake_mh.scene.Scene`.

    Attributes:
        path: the file (or the name of the data, e.g. an archive member).
        format: a key of :data:`drake_mh.scene.files.SCENE_FORMATS`.
        obstacles: :class:`~drake_mh.scene.Obstacle` s in the file's order; ``X_WO`` is the pose
            in the world, or in the frame ``frames[name]`` when the obstacle has one.
        frames: ``{obstacle name: frame name}`` for obstacles posed in a frame other than the
            world (a planning scene's ``header.frame_id``): :meth:`resolved` places them.
        name: the scene's name when the file gives one.
        robot_state: ``{joint name: position}`` when the file carries a robot state (a planning
            scene's ``robot_state.joint_state``), else empty. Not applied to anything.
    """

    path: str
    format: str
    obstacles: tuple
    frames: dict = field(default_factory=dict)
    name: str = ""
    robot_state: dict = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        """The obstacles' names, in order."""
        return [o.name for o in self.obstacles]

    def __getitem__(self, name: str) -> Obstacle:
        for obstacle in self.obstacles:
            if obstacle.name == name:
                return obstacle
        raise KeyError(name)

    def resolved(self, robot) -> tuple:
        """The obstacles with every pose in the world frame.

        A frame of :data:`WORLD_FRAMES` is the world. Any other frame must be a frame of
        ``robot`` on a body welded to the world (a fixed base link such as ``panda_link0``):
        its pose is the same at every configuration.

        Raises:
            SceneFileError: a frame the robot does not have, or one that moves with its joints.
        """
        if not self.frames:
            return self.obstacles
        plant = robot.plant
        welded = {b.index() for b in plant.GetBodiesWeldedTo(plant.world_body())}
        context = plant.CreateDefaultContext()
        out = []
        for obstacle in self.obstacles:
            frame = self.frames.get(obstacle.name, "")
            if frame in WORLD_FRAMES:
                out.append(obstacle)
                continue
            name = frame.lstrip("/")
            entry = f"obstacle {obstacle.name!r}"
            if not plant.HasFrameNamed(name):
                raise SceneFileError(self.path, f"its pose is given in frame {frame!r}, which is neither the world "
                                                f"({', '.join(repr(f) for f in WORLD_FRAMES[1:])}) nor a frame of "
                                                f"robot {robot.name!r} (its links: {', '.join(robot.link_names())})",
                                     entry)
            drake_frame = plant.GetFrameByName(name)
            if drake_frame.body().index() not in welded:
                raise SceneFileError(self.path, f"its pose is given in frame {frame!r}, which moves with the joints of "
                                                f"robot {robot.name!r}; an obstacle must be posed in the world or a "
                                                "frame welded to it", entry)
            X_WF = drake_frame.CalcPoseInWorld(context).GetAsMatrix4()
            out.append(Obstacle(obstacle.name, obstacle.shape, X_WF @ obstacle.X_WO, obstacle.velocity_W))
        return tuple(out)


class SceneFileBuilder:
    """Collects a file's obstacles, checking each entry (module docstring).

    Args:
        path: the file (for messages, and the folder relative file names resolve against).
        format: a key of :data:`drake_mh.scene.files.SCENE_FORMATS`.
        folder: the folder relative file names resolve against (default the file's; ``None``
            when the data came from elsewhere: only absolute names then).
    """

    def __init__(self, path, format: str, folder=""):
        self.path = str(path)
        self.format = format
        if folder == "":
            folder = Path(self.path).expanduser().resolve().parent
        self.folder = None if folder is None else Path(folder)
        self._obstacles: dict[str, Obstacle] = {}
        self._frames: dict[str, str] = {}

    def error(self, reason: str, entry: str = "") -> SceneFileError:
        """The error to raise for ``entry`` (not raised here)."""
        return SceneFileError(self.path, reason, entry)

    # --- numbers -----------------------------------------------------------------------------

    def numbers(self, value, count: int, what: str, entry: str) -> np.ndarray:
        """``(count,)`` finite floats, or an error saying ``what`` was expected."""
        ok = not isinstance(value, (str, bytes, bool, dict)) and value is not None
        try:
            arr = np.asarray(value, dtype=float).reshape(-1) if ok else None
        except (TypeError, ValueError):
            arr = None
        if arr is None or arr.shape != (count,) or not np.all(np.isfinite(arr)) \
                or any(isinstance(v, bool) for v in np.ravel(np.asarray(value, dtype=object))):
            raise self.error(f"{what} must be {count} finite number{'s' if count > 1 else ''}, got {value!r}", entry)
        return arr

    def number(self, value, what: str, entry: str) -> float:
        """One finite float."""
        return float(self.numbers([value] if np.ndim(value) == 0 else value, 1, what, entry)[0])

    def rotation(self, w, x, y, z, entry: str, order: str) -> np.ndarray:
        """``R (3, 3)`` of a quaternion (:func:`quaternion_matrix`); ``order`` names how the file
        writes it, for the message."""
        values = self.numbers([w, x, y, z], 4, f"the quaternion ({order})", entry)
        R = quaternion_matrix(*values)
        if R is None:
            raise self.error(f"the quaternion ({order}) {values.tolist()} has norm {np.linalg.norm(values):.6g}; a "
                             "rotation needs a unit quaternion (check the order of its numbers)", entry)
        return R

    # --- shapes ------------------------------------------------------------------------------

    def shape(self, factory, *args, entry: str):
        """``factory(*args)`` (a shape of :mod:`drake_mh.geometry.shapes`), its error named."""
        try:
            return factory(*args)
        except DrakeMhError as exc:
            raise self.error(str(exc), entry) from exc

    def file(self, name, entry: str, packages=None) -> Path:
        """The existing file that ``name`` refers to: a path (relative to :attr:`folder`),
        ``file://`` or ``package://`` (:class:`drake_mh.robot.packages.UriResolver`)."""
        from drake_mh.robot.packages import UriResolver

        if not isinstance(name, (str, os.PathLike)) or not str(name).strip():
            raise self.error(f"a file name is expected, got {name!r}", entry)
        resolver = UriResolver(self.folder, packages, source=self.path)
        try:
            return resolver.resolve(os.path.expanduser(str(name)))
        except DrakeMhError as exc:
            raise self.error(str(exc), entry) from exc

    def mesh(self, name, scale, entry: str, packages=None):
        """A :class:`drake_mh.geometry.Mesh` from a file name (:meth:`file`) and a scale."""
        from drake_mh.geometry.mesh import Mesh

        path = self.file(name, entry, packages)
        try:
            return Mesh(path, scale)
        except DrakeMhError as exc:
            raise self.error(str(exc), entry) from exc

    def inline_mesh(self, vertices, faces, entry: str):
        """A :class:`drake_mh.geometry.Mesh` of vertices ``(V, 3)`` [m] and triangles ``(F, 3)``
        (0-based) written in the file: kept as an ``.obj`` in the cache folder, named by its
        content (the same triangles give the same file)."""
        from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash

        try:
            V = np.asarray(vertices, dtype=float).reshape(-1, 3)
            F = np.asarray(faces, dtype=float).reshape(-1, 3)
        except (TypeError, ValueError):
            raise self.error("a mesh needs vertices (x, y, z) and triangles of 3 vertex indices", entry) from None
        if not (np.all(np.isfinite(V)) and np.all(F == np.round(F)) and len(F) and len(V)
                and F.min() >= 0 and F.max() < len(V)):
            raise self.error(f"a mesh needs finite vertices and triangles of 3 vertex indices in [0, {len(V)}); got "
                             f"{len(V)} vertices and {len(F)} triangles", entry)
        text = "".join(f"v {a!r} {b!r} {c!r}\n" for a, b, c in V.tolist())
        text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F.astype(np.int64).tolist())
        path = cache_dir("scene_meshes") / f"{content_hash('drake_mh-inline-mesh', text)[:24]}.obj"
        if not path.is_file():
            atomic_write_bytes(path, text.encode())
        return self.mesh(path, 1.0, entry)

    def cloud(self, points, name, radius, scale, entry: str, packages=None):
        """A :class:`drake_mh.geometry.PointCloud` from inline ``points`` or a file ``name``."""
        from drake_mh.geometry.cloud import PointCloud

        try:
            if name is not None:
                return PointCloud.from_file(self.file(name, entry, packages), radius, scale)
            return PointCloud(points, radius)
        except DrakeMhError as exc:
            raise self.error(str(exc), entry) from exc

    # --- obstacles ---------------------------------------------------------------------------

    def add(self, name, shape, X: np.ndarray, entry: str, velocity=None, frame: str = "") -> None:
        """Keep an obstacle; ``X`` is its pose in the world, or in ``frame``."""
        if not isinstance(name, str) or not name:
            raise self.error(f"an obstacle needs a non-empty name, got {name!r}", entry)
        if name in self._obstacles:
            raise self.error(f"a second obstacle named {name!r}; obstacle names must be unique", entry)
        v = np.zeros(3) if velocity is None else velocity
        self._obstacles[name] = Obstacle(name, shape, np.array(X, dtype=float), np.array(v, dtype=float))
        if frame not in WORLD_FRAMES:
            self._frames[name] = frame

    def result(self, name: str = "", robot_state: dict | None = None) -> SceneFile:
        """The :class:`SceneFile` of what was added."""
        return SceneFile(self.path, self.format, tuple(self._obstacles.values()), dict(self._frames), name or "",
                         dict(robot_state or {}))


def read_yaml(path: Path, text: str | None = None):
    """The YAML document of ``path`` (``text`` if already read), a syntax error named by line."""
    import yaml

    if text is None:
        text = read_text(path)
    try:
        return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise SceneFileError(path, f"not valid YAML ({problem})", where) from None


def read_text(path: Path) -> str:
    """The file's text (UTF-8), or an error saying why it cannot be read."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SceneFileError(path, f"not a text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise SceneFileError(path, f"cannot be read ({exc.strerror or exc})") from None
