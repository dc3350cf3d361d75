"""Mesh obstacles: a triangle mesh read from a file, scaled, in its own frame O.

:class:`Mesh` reads the file once, when it is made, and keeps the scaled surface
(``vertices (V, 3)`` [m], ``faces (F, 3)``) and a content digest (the file's bytes and the
scale) that names the mesh in caches. Formats:

* ``.stl``, ``.obj``, ``.dae`` (COLLADA, its ``<unit meter>`` applied as ROS tools do),
  ``.ply``, ``.off``, ``.gltf`` / ``.glb``: read with trimesh (a glTF scene is flattened with
  its node transforms);
* ``.vtk``: a tetrahedral volume mesh as Drake reads it, taken as its convex hull (Drake's own
  ``Mesh(...).GetConvexHull()``).

How a scene checks a mesh (one convex piece, or a convex decomposition that covers it) is in
:mod:`drake_mh.geometry.convex_pieces`.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_mh._support.cache import content_hash
from drake_mh.errors import ObstacleFileError, ObstacleFileNotFound
from drake_mh.geometry.obj_files import obj_bytes

__all__ = ["Mesh", "MESH_SUFFIXES", "collada_unit", "read_surface"]

MESH_SUFFIXES = (".stl", ".obj", ".dae", ".ply", ".off", ".gltf", ".glb", ".vtk")
"""File suffixes :class:`Mesh` reads (case-insensitive)."""


def collada_unit(path: Path) -> float:
    """The ``<unit meter="...">`` of a COLLADA file's asset (1 when absent or unreadable)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(16384).decode("utf-8", "replace")
    except OSError:
        return 1.0
    match = re.search(r"<unit\b[^>]*\bmeter\s*=\s*[\"']([^\"']+)[\"']", head)
    try:
        value = float(match.group(1)) if match else 1.0
    except ValueError:
        return 1.0
    return value if np.isfinite(value) and value > 0 else 1.0


def _scale3(scale, path) -> tuple:
    """``scale`` as 3 positive finite factors (one number is used for x, y and z)."""
    bad = ObstacleFileError(path, f"scale must be a positive number or 3 positive numbers (x, y, z), got {scale!r}")
    if isinstance(scale, (bool, str, bytes)) or scale is None or np.iscomplexobj(scale):
        raise bad
    try:
        values = np.asarray(scale, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise bad from None
    if values.shape == (1,):
        values = np.repeat(values, 3)
    if values.shape != (3,) or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise bad
    return tuple(float(v) for v in values)


def _checked_path(path) -> Path:
    if not isinstance(path, (str, os.PathLike)) or not str(path):
        raise ObstacleFileError(repr(path), "expected the path of a file (str or pathlib.Path)")
    path = Path(path).expanduser()
    if not path.is_file():
        raise ObstacleFileNotFound(path, "no such file; give the path of an existing file "
                                         "(relative paths are read from the current folder)")
    return path.resolve()


def read_surface(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3), faces (F, 3) int64)`` of the mesh file ``path``, in the file's units.

    Raises:
        ObstacleFileError: a format not in :data:`MESH_SUFFIXES`, a file the reader rejects, no
            triangle, or a vertex that is not finite.
    """
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise ObstacleFileError(path, f"unknown mesh format {suffix or '(no suffix)'!r}; "
                                      f"use one of {', '.join(MESH_SUFFIXES)}")
    if suffix == ".vtk":
        vertices = _drake_hull_vertices(path)
        from scipy.spatial import ConvexHull

        faces = ConvexHull(vertices).simplices
    else:
        import trimesh

        try:
            mesh = trimesh.load(str(path), force="mesh", process=False)
        except Exception as exc:  # trimesh raises many kinds (ValueError, KeyError, ImportError ...)
            raise ObstacleFileError(path, f"cannot read the mesh ({type(exc).__name__}: {exc}); "
                                          "export it again as .stl or .obj") from exc
        vertices = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), dtype=float).reshape(-1, 3)
        faces = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
        if suffix == ".dae":
            vertices = vertices * collada_unit(path)  # ROS tools (assimp) scale by <unit meter>; trimesh does not
    if len(faces) == 0 or len(vertices) < 3:
        raise ObstacleFileError(path, f"the file holds no triangle ({len(vertices)} vertices, {len(faces)} faces); "
                                      "a mesh obstacle needs a surface")
    if not np.all(np.isfinite(vertices)):
        raise ObstacleFileError(path, "the mesh has vertices that are not finite numbers (NaN or inf)")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ObstacleFileError(path, "the mesh has faces that name vertices it does not have")
    return np.ascontiguousarray(vertices), np.ascontiguousarray(faces)


def _drake_hull_vertices(path: Path) -> np.ndarray:
    from pydrake.geometry import Mesh as DrakeMesh

    try:
        hull = DrakeMesh(str(path)).GetConvexHull()
    except Exception as exc:  # Drake raises RuntimeError with its parser's message
        message = str(exc).strip().splitlines()[-1] if str(exc).strip() else type(exc).__name__
        raise ObstacleFileError(path, f"Drake cannot read this .vtk file ({message}); "
                                      "export the surface as .obj or .stl instead") from exc
    return np.array([hull.vertex(i) for i in range(hull.num_vertices())], dtype=float).reshape(-1, 3)


@dataclass(frozen=True, eq=False, init=False)
class Mesh:
    """A triangle-mesh obstacle, read from ``path`` and scaled by ``scale``.

    Args:
        path: a mesh file (:data:`MESH_SUFFIXES`), read once, now.
        scale: one positive factor, or three (x, y, z), applied to the file's coordinates (files
            in millimetres: ``scale=0.001``).

    Attributes:
        path: the file (absolute).
        scale: ``(sx, sy, sz)``.
        vertices: ``(V, 3)`` [m] the scaled vertices, in the obstacle's frame O.
        faces: ``(F, 3)`` int64 triangles (indices of ``vertices``).
        digest: SHA-256 of the file's bytes and the scale: names the mesh in caches.

    Raises:
        ObstacleFileNotFound: no such file.
        ObstacleFileError: an unknown format, an unreadable or empty file, vertices that are not
            finite, a mesh with no volume (all in a plane), a scale that is not one or three
            positive numbers.
    """

    path: Path
    scale: tuple
    vertices: np.ndarray
    faces: np.ndarray
    digest: str

    def __init__(self, path, scale=1.0):
        path = _checked_path(path)
        scale3 = _scale3(scale, path)
        vertices, faces = read_surface(path)
        vertices = vertices * np.asarray(scale3)
        extent = np.ptp(vertices, axis=0)
        if np.linalg.matrix_rank(vertices - vertices.mean(axis=0), tol=1e-9 * max(1.0, float(extent.max()))) < 3:
            raise ObstacleFileError(path, "the mesh is flat (all its vertices lie in a plane or on a line): "
                                          "an obstacle needs a volume; give a thin plate a thickness")
        vertices.setflags(write=False)
        faces.setflags(write=False)
        digest = content_hash("drake_mh-mesh-obstacle", path.read_bytes(), np.asarray(scale3).tobytes())
        for name, value in (("path", path), ("scale", scale3), ("vertices", vertices), ("faces", faces),
                            ("digest", digest)):
            object.__setattr__(self, name, value)

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3)`` [m] the lowest and highest vertex coordinates, in O."""
        return np.array([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def is_convex(self) -> bool:
        """Whether the mesh is a closed convex surface: watertight, and its volume equals its
        convex hull's (to 1e-6 relative). Such a mesh is checked as one convex piece."""
        import trimesh

        mesh = trimesh.Trimesh(self.vertices, self.faces, process=True)
        if not mesh.is_watertight:
            return False
        hull = mesh.convex_hull.volume
        return bool(hull > 0 and abs(abs(mesh.volume) - hull) <= 1e-6 * hull)

    @property
    def circumradius(self) -> float:
        """Radius [m] of the smallest origin-centred ball that holds the mesh and its convex
        pieces grown by their cover excess."""
        from drake_mh.geometry.convex_pieces import convex_pieces

        pieces = convex_pieces(self)
        return float(max(np.linalg.norm(np.concatenate(pieces.vertices), axis=1).max(),
                         np.linalg.norm(self.vertices, axis=1).max()) + pieces.excess)

    def signed_distance(self, p_O: np.ndarray) -> np.ndarray:
        """A lower bound ``(...)`` [m] of the signed distance of points ``p_O (..., 3)`` (in O) to
        the mesh: the smallest over its convex pieces (grown by their cover excess) of their
        plane bound (:meth:`drake_mh.geometry.convex_pieces.ConvexPieces.signed_distance_bound`);
        exact inside a piece."""
        from drake_mh.geometry.convex_pieces import convex_pieces

        return convex_pieces(self).signed_distance_bound(p_O)

    def obj_file(self) -> Path:
        """The scaled surface as a cached ``.obj`` file (under ``cache_dir("meshes")``), for
        Drake and Meshcat, which read ``.obj`` but not every format :class:`Mesh` does."""
        from drake_mh._support.cache import atomic_write_bytes, cache_dir

        path = cache_dir("meshes") / f"{self.digest[:32]}_obstacle.obj"
        if not path.is_file():
            atomic_write_bytes(path, obj_bytes(self.vertices, self.faces, f"{self.path.name} scaled (drake_mh)"))
        return path

    def to_drake(self):
        """A ``pydrake.geometry.Mesh`` of the scaled surface (:meth:`obj_file`): for Meshcat and
        illustration. Drake's proximity queries would use its convex hull; a
        :class:`drake_mh.scene.Scene` checks the convex pieces instead
        (:mod:`drake_mh.geometry.convex_pieces`)."""
        from pydrake.geometry import Mesh as DrakeMesh

        return DrakeMesh(str(self.obj_file()))

    def __eq__(self, other) -> bool:
        return isinstance(other, Mesh) and other.digest == self.digest

    def __hash__(self) -> int:
        return hash(self.digest)

    def __repr__(self) -> str:
        scale = self.scale[0] if len(set(self.scale)) == 1 else self.scale
        return (f"Mesh({str(self.path)!r}, scale={scale!r}, vertices={len(self.vertices)}, "
                f"faces={len(self.faces)}, digest={self.digest[:12]!r})")
