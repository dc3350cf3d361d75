"""Mesh files of robot models turned into what Drake accepts, cached on disk.

* **Collision** meshes in any format trimesh reads (``.stl``, ``.dae`` (with pycollada),
  ``.obj``, ``.ply``, ``.off``, ``.glb`` ...) become their **convex hull** written as ``.obj``
  — Drake's proximity engine uses the convex hull of a mesh anyway, and builds it only from
  ``.obj``/``.vtk``/``.gltf`` files. The model is then told the shape is convex
  (``<drake:declare_convex/>``), so the plant holds a ``Convex`` shape whose file is the hull.
* **Visual** meshes stay as they are when Meshcat shows them (``.obj``, ``.gltf``, ``.dae``);
  others (``.stl``, ``.ply`` ...) are converted to ``.obj`` (the whole mesh, not its hull).

Converted files live in ``cache_dir("meshes")`` (``$DRAKE_MH_CACHE/meshes``, see
:mod:`drake_mh._support.cache`) under the SHA-256 of the source file's bytes, its extension and the
conversion kind, so an edited mesh gets a new entry and a second load reads the file it wrote.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash
from drake_mh.errors import MeshConversionError
from drake_mh.geometry.mesh import collada_unit
from drake_mh.geometry.obj_files import obj_bytes

logger = logging.getLogger(__name__)

MESHCAT_VISUAL_SUFFIXES = (".obj", ".gltf", ".dae")
"""Mesh formats Drake's Meshcat displays (measured with drake 1.51: ``.stl`` is not shown)."""

_VERSION = "2"  # bump when the conversion changes, so old cache entries are not reused


def _load_trimesh(path: Path):
    try:
        import trimesh
    except ImportError as exc:  # pragma: no cover - trimesh is a dependency
        raise MeshConversionError(str(path), "the 'trimesh' package is not installed "
                                  "(pip install trimesh pycollada)") from exc
    try:
        mesh = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds (ValueError, KeyError, ImportError ...)
        raise MeshConversionError(str(path), f"{type(exc).__name__}: {exc}") from exc
    if path.suffix.lower() == ".dae":
        scale = collada_unit(path)
        if scale != 1.0:  # ROS tools (assimp) scale by <unit meter>; trimesh does not
            mesh.apply_scale(scale)
    vertices = np.asarray(getattr(mesh, "vertices", np.zeros((0, 3))), dtype=float)
    if vertices.ndim != 2 or vertices.shape[0] < 4 or not np.all(np.isfinite(vertices)):
        raise MeshConversionError(str(path), f"the file holds {len(vertices)} finite vertices, "
                                  "a convex hull needs at least 4 that are not coplanar")
    return mesh


def _cached(path: Path, kind: str, make) -> Path:
    data = path.read_bytes()
    key = content_hash("drake_mh-mesh", _VERSION, kind, path.suffix.lower(), data)
    out = cache_dir("meshes") / f"{key[:32]}_{kind}.obj"
    if out.is_file():
        return out
    atomic_write_bytes(out, make())
    logger.info("converted %s -> %s (%s)", path, out, kind)
    return out


def collision_hull(path: str | Path) -> Path:
    """The convex hull of a mesh file as a cached ``.obj`` (vertices in the file's own units).

    Args:
        path: an existing mesh file.

    Returns:
        Path of the hull ``.obj`` in the cache.

    Raises:
        MeshConversionError: the file cannot be read or has no 3-D hull (flat or < 4 points).
    """
    path = Path(path)

    def make() -> bytes:
        mesh = _load_trimesh(path)
        try:
            hull = mesh.convex_hull
        except Exception as exc:  # qhull errors on flat / degenerate point sets
            raise MeshConversionError(str(path), f"no 3-D convex hull ({exc})") from exc
        if len(hull.faces) < 4:
            raise MeshConversionError(str(path), "the mesh is flat (its hull has no volume)")
        return obj_bytes(np.asarray(hull.vertices), np.asarray(hull.faces),
                          f"convex hull of {path.name} (drake_mh)")

    return _cached(path, "hull", make)


def visual_mesh(path: str | Path) -> Path:
    """A file Meshcat can show for a visual mesh: the file itself, or a cached ``.obj``.

    Raises:
        MeshConversionError: a format Meshcat cannot show that trimesh cannot read either.
    """
    path = Path(path)
    if path.suffix.lower() in MESHCAT_VISUAL_SUFFIXES:
        return path

    def make() -> bytes:
        mesh = _load_trimesh(path)
        return obj_bytes(np.asarray(mesh.vertices), np.asarray(mesh.faces),
                          f"{path.name} converted for Meshcat (drake_mh)")

    return _cached(path, "visual", make)
