"""A conservative sphere model of a robot, derived from its Drake collision geometry.

Metaheuristics evaluate clearance for whole populations, so the hot path cannot call Drake's
exact distance per configuration. :class:`SphereModel` covers every collision geometry of
every link (sphere, capsule, cylinder, box, ellipsoid, and ``Convex`` / ``Mesh`` through their
convex hull, which is what Drake's distance queries use) with spheres whose union *contains*
the geometry, and every point of whose spheres lies within ``link_bound[link]`` of it
(:mod:`drake_mh.geometry.sphere_cover` gives the construction and the proof; the bound is at most the
tolerance, 1 cm by default).

The guarantee :class:`drake_mh.scene.Scene` derives from it, per obstacle, with ``d`` the true
signed distance of the robot's collision geometry to the obstacle and ``m`` the model's value
(``bound`` = the largest ``link_bound``):

* ``m <= d`` for every configuration, penetration included (to round-off, 1e-9 m): the model
  never reports more clearance than there is, and never reports a colliding configuration as
  free (``d < 0`` implies ``m < 0``).
* ``d - bound <= m`` wherever ``d >= 0``: the model is at most ``bound`` pessimistic (plus 2 % of
  a cylinder obstacle's radius, handled as its circumscribed 16-gon prism in penetration).

Drake's own value can be optimistic where it runs GJK (mesh, box or cylinder links against box,
cylinder or capsule obstacles; :class:`drake_mh.scene.Scene` refines the capsule cases), so
against Drake ``m <= d`` holds a fortiori and the pessimism can read up to Drake's error more.

Why penetration needs care: the per-sphere signed distance is the obstacle's depth inside *one*
sphere, while the obstacle can be deeper inside the covered geometry than inside any single
sphere (a ball obstacle centred on a capsule's axis between two sphere centres: up to 7.8 mm
shallower on the Panda). Where a sphere reports penetration, :mod:`drake_mh.scene.penetration`
replaces the value by a lower bound of the exact one computed from each geometry's *core* (its
axis segment or its bounding polytope).

Models are cached on disk (:func:`drake_mh._support.cache.cache_dir` ``("spheres")``) by a content hash of
each geometry's shape, the tolerance and :data:`ALGORITHM_VERSION`, so a mesh robot's second
load does not recompute its covering.
"""

from __future__ import annotations

import functools
import io
import logging
import zipfile
from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import InvalidArgument, SceneError
from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere, from_drake
from drake_mh.geometry.sphere_cover import circumscribed_polytope, cover

log = logging.getLogger(__name__)

DEFAULT_TOLERANCE = 0.01
"""Default covering tolerance [m]: every sphere point lies within it of the geometry."""

ALGORITHM_VERSION = "sphere-cover-3"
"""Part of every cache key: change it whenever :mod:`drake_mh.geometry.sphere_cover` changes its output."""

SEGMENT, POLYTOPE = 0, 1


@dataclass(frozen=True, eq=False)
class GeometryCore:
    """One collision geometry of a link, as the penetration correction needs it.

    Attributes:
        link: the link's name.
        X_BG: ``(4, 4)`` pose of the geometry frame G in the link frame B.
        kind: :data:`SEGMENT` (a capsule or sphere: the points within ``radius`` of the segment
            ``z in [-half_length, half_length]`` of G) or :data:`POLYTOPE` (a polytope containing
            the geometry, within ``hausdorff`` of it).
        half_length, radius: the segment core [m].
        normals_G, offsets: the polytope ``normals_G @ p + offsets <= 0`` (outward unit normals).
        vertices_G: ``(V, 3)`` the polytope's vertices [m].
        edges_G: ``(E, 3)`` the polytope's edge directions, one per direction up to sign.
        excess: every sphere point of this geometry lies within this of it [m].
    """

    link: str
    X_BG: np.ndarray
    kind: int
    half_length: float = 0.0
    radius: float = 0.0
    normals_G: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    offsets: np.ndarray = field(default_factory=lambda: np.zeros(0))
    vertices_G: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    edges_G: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    excess: float = 0.0


def _shape_key(shape) -> str:
    """A string identifying ``shape`` exactly (for cache keys)."""
    if isinstance(shape, ConvexPolytope):
        from drake_mh._support.cache import content_hash

        return "ConvexPolytope:" + content_hash(shape.fingerprint())
    return repr(shape)


def _cover_cached(shape, tolerance: float, use_cache: bool):
    """:func:`drake_mh.geometry.sphere_cover.cover`, cached on disk for the shapes that take time."""
    if not use_cache or isinstance(shape, (Sphere, Capsule)):
        return cover(shape, tolerance)
    from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash

    key = content_hash(ALGORITHM_VERSION, repr(float(tolerance)), _shape_key(shape))
    path = cache_dir("spheres") / f"{key}.npz"
    try:
        with np.load(path) as data:
            return data["centres"], data["radii"], float(data["excess"])
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        pass  # missing or unreadable: recompute (and overwrite)
    centres, radii, excess = cover(shape, tolerance)
    buffer = io.BytesIO()
    np.savez(buffer, centres=centres, radii=radii, excess=excess)
    try:
        atomic_write_bytes(path, buffer.getvalue())
    except OSError as exc:  # a read-only cache only costs time
        log.warning("cannot write the sphere-model cache %s: %s", path, exc)
    return centres, radii, excess


def _core(link: str, X_BG: np.ndarray, shape, tolerance: float, excess: float) -> GeometryCore:
    if isinstance(shape, Sphere):
        return GeometryCore(link, X_BG, SEGMENT, 0.0, shape.radius, excess=excess)
    if isinstance(shape, Capsule):
        return GeometryCore(link, X_BG, SEGMENT, 0.5 * shape.length, shape.radius, excess=excess)
    poly, _ = circumscribed_polytope(shape, tolerance)
    return GeometryCore(link, X_BG, POLYTOPE, normals_G=poly.normals, offsets=poly.offsets,
                        vertices_G=poly.vertices, edges_G=_edge_directions(poly), excess=excess)


def _edge_directions(poly: ConvexPolytope) -> np.ndarray:
    """``(E, 3)`` unit directions of the polytope's edges (between two facets that are not
    coplanar), one per direction up to sign."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(poly.vertices)
    tri = hull.simplices
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(tri)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    edges, owner = edges[order], owner[order]
    pair = np.flatnonzero((edges[1:] == edges[:-1]).all(axis=1))  # each edge has 2 triangles
    n = hull.equations[:, :3]
    real = np.einsum("ij,ij->i", n[owner[pair]], n[owner[pair + 1]]) < 1 - 1e-9
    e = hull.points[edges[pair[real], 1]] - hull.points[edges[pair[real], 0]]
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    e *= np.where(e[:, :1] < 0, -1.0, 1.0)  # one sign per direction
    return np.unique(np.round(e, 9), axis=0)


@dataclass(frozen=True)
class SphereModel:
    """Spheres fixed to the robot's links that cover its collision geometry.

    Attributes:
        links: ``(S,)`` link name of each sphere.
        centres_B: ``(S, 3)`` sphere centres in their link frames [m].
        radii: ``(S,)`` radii [m].
        bound: the model is at most this pessimistic [m] (max over links of ``link_bound``).
        link_bound: link name -> every sphere point of that link is within this of its geometry [m].
        tolerance: the covering tolerance used [m].
        geometry: ``(S,)`` index into ``geometries`` of the geometry each sphere covers (the
            spheres of one geometry are contiguous).
        geometries: one :class:`GeometryCore` per collision geometry.
    """

    links: tuple
    centres_B: np.ndarray
    radii: np.ndarray
    bound: float
    link_bound: dict = field(default_factory=dict)
    tolerance: float = DEFAULT_TOLERANCE
    geometry: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    geometries: tuple = ()

    @property
    def num_spheres(self) -> int:
        return len(self.links)

    @functools.cached_property
    def core_arrays(self) -> tuple:
        """``(starts (G,), kind (G,), half_length (G,), radius (G,))``: the first sphere of each
        geometry and the geometries' core data as arrays (for :mod:`drake_mh.scene.penetration`)."""
        starts = np.flatnonzero(np.r_[True, np.diff(self.geometry) != 0])
        cores = self.geometries
        return (starts, np.array([c.kind for c in cores]), np.array([c.half_length for c in cores]),
                np.array([c.radius for c in cores]))

    def link_counts(self) -> dict:
        """Link name -> number of spheres."""
        names, counts = np.unique(np.asarray(self.links), return_counts=True)
        return {str(n): int(c) for n, c in zip(names, counts)}

    @classmethod
    def from_robot(cls, robot, tolerance: float = DEFAULT_TOLERANCE, cache: bool = True) -> SphereModel:
        """Cover every proximity geometry of ``robot``'s links (read from its SceneGraph).

        Args:
            robot: a :class:`drake_mh.robot.Robot`.
            tolerance: covering tolerance [m]: every sphere point lies within it of the
                geometry. Smaller is tighter but takes more spheres: about
                ``tolerance^-1.5`` for meshes (example-robot-data's Panda: 282 / 794 / 2,174
                spheres at 2 / 1 / 0.5 cm), ``tolerance^-0.5`` for capsules.
            cache: read and write the on-disk cache (:mod:`drake_mh._support.cache`).

        Raises:
            InvalidArgument: non-positive tolerance.
            SceneError: the robot has no collision geometry on any link.
            UnsupportedGeometry: a shape that is neither a primitive nor a readable convex mesh.
        """
        from pydrake.geometry import Role

        tolerance = float(tolerance)
        if not np.isfinite(tolerance) or tolerance <= 0:
            raise InvalidArgument(f"sphere-model tolerance must be a positive length in metres, got {tolerance}")
        inspector = robot.scene_graph.model_inspector()
        links, centres, radii, link_bound, cores, owner = [], [], [], {}, [], []
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            frame_id = inspector.GetFrameId(gid)
            if frame_id == inspector.world_frame_id():
                continue  # anchored geometry is scenery, not robot
            body = robot.plant.GetBodyFromFrameId(frame_id)
            if body is None:
                continue
            shape = from_drake(inspector.GetShape(gid))
            c_G, r, excess = _cover_cached(shape, tolerance, cache)
            X_BG = inspector.GetPoseInFrame(gid).GetAsMatrix4()
            c_B = c_G @ X_BG[:3, :3].T + X_BG[:3, 3]
            name = body.name()
            link_bound[name] = max(link_bound.get(name, 0.0), excess)
            owner.extend([len(cores)] * len(r))
            cores.append(_core(name, X_BG, shape, tolerance, excess))
            links.extend([name] * len(r))
            centres.append(c_B)
            radii.append(r)
        if not links:
            raise SceneError(
                f"robot {robot.name!r} has no collision geometry, so clearance cannot be computed "
                "(a missing answer is not 'no collision'); add <collision> elements to its links "
                "in the model file, or leave obstacles out of the problem")
        return cls(tuple(links), np.vstack(centres), np.concatenate(radii), max(link_bound.values()),
                   link_bound, tolerance, np.asarray(owner, np.int64), tuple(cores))


def has_collision_geometry(robot) -> bool:
    """Whether any link of ``robot`` has proximity (collision) geometry."""
    from pydrake.geometry import Role

    inspector = robot.scene_graph.model_inspector()
    return any(inspector.GetFrameId(g) != inspector.world_frame_id()
               for g in inspector.GetAllGeometryIds(Role.kProximity))


def cover_shape(shape, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
    """Spheres ``(centres_G (S, 3), radii (S,))`` whose union contains ``shape`` (see :func:`cover`)."""
    centres, radii, _ = cover(shape, tolerance)
    return centres, radii


__all__ = ["SphereModel", "GeometryCore", "DEFAULT_TOLERANCE", "ALGORITHM_VERSION", "cover_shape",
           "has_collision_geometry", "Box", "Capsule", "Cylinder", "Ellipsoid", "Sphere", "ConvexPolytope"]
