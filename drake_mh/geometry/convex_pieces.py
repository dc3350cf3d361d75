"""The convex pieces a scene checks a mesh obstacle with, and how far the mesh may leave them.

* A convex mesh (:attr:`drake_mh.geometry.mesh.Mesh.is_convex`) whose hull has at most 32
  vertices is one piece: its convex hull (which holds every triangle: no excess).
* Any other mesh (a curved convex one too: its hull's vertices are simplified to 32, as the
  kernels test every plane of a piece) is cut into convex pieces by CoACD (Wei et al., "Approximate Convex
  Decomposition for 3D Meshes with Collision-Aware Concavity and Tree Search", SIGGRAPH 2022;
  the ``coacd`` package, parameters :data:`COACD_PARAMETERS`), a few seconds to a minute per
  mesh, so the result is cached on disk (:func:`drake_mh._support.cache.cache_dir`
  ``("convex_pieces")``) under the SHA-256 of the mesh's bytes, its scale and the parameters.

**Cover excess.** CoACD's pieces are the hulls of parts of the mesh, simplified, so they
need not contain every point of the surface. :func:`cover_excess` measures a bound ``e`` of
the distance of any surface point from the union of the pieces, and every check grows each
piece by ``e`` (the kernels' planes and bounding spheres, the exact distances' margin), so
the grown pieces cover the mesh: a check that says "free" is free of the mesh. The bound:
the surface's triangles are split until their longest edge is at most 8 mm; a triangle whose
three corners are within ``t`` of one piece lies within ``t`` of it (the piece grown by ``t``
is convex); the triangles with no piece within 0.1 mm of their three corners are split in
four, four more times (edges down to 0.5 mm), and then each adds the smaller of that and
``max_corners dist(corner, union) + longest_edge(T)`` (every point of T is within its longest
edge of a corner): :func:`cover_excess`. The corners' distances are exact.
"""

from __future__ import annotations

import functools
import io
import logging
import time
from dataclasses import dataclass

import numpy as np

from drake_mh._support.cache import atomic_write_bytes, cache_dir, content_hash
from drake_mh.errors import ObstacleFileError

__all__ = ["ConvexPieces", "convex_pieces", "cover_excess", "COACD_PARAMETERS"]

logger = logging.getLogger(__name__)

COACD_PARAMETERS = {"threshold": 0.05, "max_ch_vertex": 32, "decimate": True, "preprocess_mode": "auto",
                    "resolution": 2000, "mcts_nodes": 20, "mcts_iterations": 150, "mcts_max_depth": 3, "seed": 0}
"""CoACD's defaults (concavity ``threshold`` 0.05, seed 0), except hulls decimated to at most
32 vertices (fewer planes for the kernels to test; the cover excess measures what that costs)."""

_VERSION = "3"  # bump when the decomposition or the bound changes: old cache entries are not reused
_START_EDGE, _LEVELS, _MAX_TRIANGLES = 0.008, 4, 400_000


def _hull_planes(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(normals (F, 3), offsets (F,), simplices (T, 3))``: the distinct facet planes
    (``normals @ x <= offsets`` inside) and the triangles of the hull of ``vertices``."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(vertices)
    planes = np.unique(np.round(hull.equations, 12), axis=0)
    return planes[:, :3], -planes[:, 3], hull.simplices


@dataclass(frozen=True, eq=False)
class ConvexPieces:
    """A mesh's convex pieces in its frame O.

    Attributes:
        vertices: one ``(V_i, 3)`` array [m] per piece (the hull's vertices).
        excess: [m] the bound ``e`` of the module docstring: the mesh lies within ``e`` of the
            union of the pieces; every check grows the pieces by it.
        seconds: how long the decomposition took when it was made (not when read from the cache).
        cached: whether it was read from the disk cache.
    """

    vertices: tuple
    excess: float
    seconds: float = 0.0
    cached: bool = False

    def __len__(self) -> int:
        return len(self.vertices)

    @functools.cached_property
    def kernel_planes(self) -> tuple:
        """Per piece ``(centre (3,), radius, normals (M, 3), offsets (M,))`` in O: supporting
        planes ``normals @ (x - centre) <= offsets`` of the piece grown by :attr:`excess` —
        its facets, and the normalised sums of the facet normals at each edge and each vertex
        (tighter bounds near them: :mod:`drake_mh.scene.kernels.pieces`) — and a ball about
        ``centre`` (the middle of its bounding box) that holds the grown piece."""
        from scipy.spatial import ConvexHull

        out = []
        for V in self.vertices:
            normals, _, _ = _hull_planes(V)
            hull = ConvexHull(V)
            face = hull.equations[:, :3]
            extra = [face[:, None, :] + face[hull.neighbors]]  # each edge: the sum of its two facets' normals
            for v in range(len(V)):  # each vertex: the sum of the distinct facet normals that touch it
                touching = normals[np.abs(normals @ V[v] - (V @ normals.T).max(axis=0)) <= 1e-9]
                extra.append(touching.sum(axis=0))
            extra = np.vstack([np.asarray(e).reshape(-1, 3) for e in extra])
            extra = extra[np.linalg.norm(extra, axis=1) > 1e-9]
            directions = np.vstack([normals, extra / np.linalg.norm(extra, axis=1, keepdims=True)])
            directions = np.unique(np.round(directions, 9), axis=0)
            directions /= np.linalg.norm(directions, axis=1, keepdims=True)
            centre = 0.5 * (V.min(axis=0) + V.max(axis=0))
            offsets = (V - centre) @ directions.T
            out.append((centre, float(np.linalg.norm(V - centre, axis=1).max() + self.excess),
                        np.ascontiguousarray(directions), np.ascontiguousarray(offsets.max(axis=0) + self.excess)))
        return tuple(out)

    @functools.cached_property
    def drake_shapes(self) -> tuple:
        """``((centre (3,), Convex), ...)``: each piece as a ``pydrake.geometry.Convex`` (from
        memory, not grown by :attr:`excess`) about the centre of :attr:`kernel_planes`, in O."""
        from pydrake.common import MemoryFile
        from pydrake.geometry import Convex, InMemoryMesh

        from drake_mh.geometry.obj_files import obj_bytes

        out = []
        for i, (V, (centre, *_)) in enumerate(zip(self.vertices, self.kernel_planes)):
            data = obj_bytes(V - centre, _hull_planes(V)[2], f"convex piece {i}").decode()
            out.append((centre, Convex(InMemoryMesh(mesh_file=MemoryFile(data, ".obj", f"piece{i}.obj")))))
        return tuple(out)

    def signed_distance_bound(self, p_O: np.ndarray) -> np.ndarray:
        """``(...)`` [m] a lower bound of the signed distance of points ``p_O (..., 3)`` to the
        mesh: the smallest over the pieces of their plane bound (:attr:`kernel_planes`)."""
        p = np.asarray(p_O, dtype=float)
        out = np.full(p.shape[:-1], np.inf)
        for centre, _, normals, offsets in self.kernel_planes:
            out = np.minimum(out, ((p - centre) @ normals.T - offsets).max(axis=-1))
        return out

    def to_bytes(self) -> bytes:
        buf = io.BytesIO()
        np.savez(buf, vertices=np.concatenate(self.vertices), counts=[len(v) for v in self.vertices],
                 excess=self.excess, seconds=self.seconds)
        return buf.getvalue()

    @classmethod
    def from_bytes(cls, data: bytes) -> ConvexPieces:
        with np.load(io.BytesIO(data)) as npz:
            parts = np.split(npz["vertices"], np.cumsum(npz["counts"])[:-1])
            return cls(tuple(np.ascontiguousarray(p) for p in parts), float(npz["excess"]), float(npz["seconds"]),
                       cached=True)


def _split4(tris: np.ndarray) -> np.ndarray:
    """Each triangle of ``tris (T, 3, 3)`` as its four midpoint triangles ``(4T, 3, 3)``."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
    return np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def _longest_edge(tris: np.ndarray) -> np.ndarray:
    return np.max(np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=2), axis=1)


def _exact_distances(points: np.ndarray, V: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """Exact distance [m] of each of ``points (n, 3)`` (outside the piece) to the convex piece
    with hull triangles ``V[simplices]``: the nearest of the closest points on its triangles."""
    from trimesh.triangles import closest_point

    tri = V[simplices]
    out = np.empty(len(points))
    step = max(1, 20000 // len(tri))
    for start in range(0, len(points), step):
        chunk = points[start:start + step]
        P = np.repeat(chunk, len(tri), axis=0)
        T = np.tile(tri, (len(chunk), 1, 1))
        out[start:start + step] = np.linalg.norm(closest_point(T, P) - P, axis=1).reshape(len(chunk), -1).min(axis=1)
    return out


def _corner_distances(corners: np.ndarray, hulls: list, chunk: int = 20000) -> np.ndarray:
    """:func:`_chunk_distances` a ``chunk`` of corners at a time (bounded memory)."""
    return np.concatenate([_chunk_distances(corners[i:i + chunk], hulls) for i in range(0, len(corners), chunk)]
                          or [np.zeros((0, len(hulls)))])


def _chunk_distances(corners: np.ndarray, hulls: list) -> np.ndarray:
    """``(n, P)`` [m]: the distance of each corner to each piece (0 inside; exact), ``inf``
    where it is more than 1 cm (outside the piece's bounding box grown by 1 cm) and another
    piece is nearer.

    A corner beyond exactly one facet plane whose projection on it lies in the piece is at the
    plane's distance; the others get :func:`_exact_distances`."""
    D = np.full((len(corners), len(hulls)), np.inf)
    near = np.zeros((len(corners), len(hulls)), bool)
    for p, (V, _, _, _) in enumerate(hulls):
        near[:, p] = ((corners >= V.min(axis=0) - 0.01) & (corners <= V.max(axis=0) + 0.01)).all(axis=1)
    near[~near.any(axis=1)] = True  # no piece within 1 cm: every piece, exactly
    for p, (V, normals, offsets, simplices) in enumerate(hulls):
        rows = np.flatnonzero(near[:, p])
        x = corners[rows]
        excess = x @ normals.T - offsets
        worst = excess.argmax(axis=1)
        lb = np.maximum(excess[np.arange(len(x)), worst], 0.0)
        d = np.full(len(x), np.nan)
        d[lb <= 1e-12] = 0.0
        single = (lb > 1e-12) & ((excess > 1e-12).sum(axis=1) == 1)
        projected = x[single] - lb[single, None] * normals[worst[single]]
        on_face = ((projected @ normals.T - offsets) <= 1e-9).all(axis=1)
        d[np.flatnonzero(single)[on_face]] = lb[single][on_face]
        rest = np.isnan(d)
        if rest.any():
            d[rest] = _exact_distances(x[rest], V, simplices)
        D[rows, p] = d
    return D


def cover_excess(vertices: np.ndarray, faces: np.ndarray, pieces) -> float:
    """The bound ``e`` [m] of the module docstring: every point of the triangles
    ``vertices[faces]`` lies within ``e`` of the union of the convex ``pieces`` (each a
    ``(V_i, 3)`` array of hull vertices).

    Per triangle T (corners c, pieces p, exact corner distances ``D[c, p]``): T lies in the
    convex set ``p ⊕ B(max_c D[c, p])``, and every point of T is within ``longest_edge(T)`` of
    a corner, so T adds ``min(min_p max_c D[c, p], max_c min_p D[c, p] + longest_edge(T))``.
    Triangles where the first term exceeds 0.1 mm are split in four (:data:`_LEVELS` times)."""
    hulls = [(np.asarray(V, dtype=float),) + _hull_planes(np.asarray(V, dtype=float)) for V in pieces]
    tris = np.asarray(vertices, dtype=float)[np.asarray(faces)]
    while True:  # split until the longest edge is at most the start length
        long = _longest_edge(tris) > _START_EDGE
        if not long.any() or len(tris) + 3 * np.count_nonzero(long) > _MAX_TRIANGLES:
            break
        tris = np.concatenate([tris[~long], _split4(tris[long])])
    excess = 0.0
    for level in range(_LEVELS + 1):
        D = _corner_distances(tris.reshape(-1, 3), hulls).reshape(len(tris), 3, len(hulls))
        within = D.max(axis=1).min(axis=1)  # T inside one grown piece
        bound = np.minimum(within, D.min(axis=2).max(axis=1) + _longest_edge(tris))
        settle = within <= 1e-4
        if level == _LEVELS or 4 * np.count_nonzero(~settle) > _MAX_TRIANGLES:
            return float(max(excess, bound.max(initial=0.0)))
        excess = max(excess, float(within[settle].max(initial=0.0)))
        tris = _split4(tris[~settle])
        if not len(tris):
            return excess


@functools.lru_cache(maxsize=64)
def convex_pieces(mesh) -> ConvexPieces:
    """The convex pieces of a :class:`drake_mh.geometry.mesh.Mesh` (module docstring), from the
    disk cache when there (kept in memory too, per mesh).

    Raises:
        ObstacleFileError: CoACD fails on the mesh (or returns no piece with a volume).
    """
    key = content_hash("drake_mh-convex-pieces", _VERSION, mesh.digest, repr(sorted(COACD_PARAMETERS.items())))
    path = cache_dir("convex_pieces") / f"{key[:32]}.npz"
    if path.is_file():
        try:
            return ConvexPieces.from_bytes(path.read_bytes())
        except (OSError, ValueError, KeyError):
            logger.warning("unreadable cache entry %s: decomposing again", path)
    start = time.perf_counter()
    from scipy.spatial import ConvexHull

    hull = mesh.vertices[ConvexHull(mesh.vertices).vertices]
    convex = mesh.is_convex and len(hull) <= COACD_PARAMETERS["max_ch_vertex"]
    if convex:
        parts = [hull]  # holds every triangle: no excess
    else:  # not convex, or a hull of many vertices (a curved mesh) that CoACD simplifies
        import coacd

        coacd.set_log_level("error")
        try:
            result = coacd.run_coacd(coacd.Mesh(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces)),
                                     **COACD_PARAMETERS)
        except (RuntimeError, ValueError, MemoryError) as exc:  # what coacd's bindings raise
            raise ObstacleFileError(mesh.path, f"no convex decomposition ({type(exc).__name__}: {exc}); repair the "
                                               "mesh (close its holes) or give its convex parts as separate "
                                               "meshes") from exc
        parts = [np.asarray(v, dtype=float) for v, _ in result if len(v) >= 4]
        if not parts:
            raise ObstacleFileError(mesh.path, "the convex decomposition returned no piece with a volume; repair "
                                               "the mesh or give its convex parts as separate meshes")
    excess = 0.0 if convex else cover_excess(mesh.vertices, mesh.faces, parts)
    pieces = ConvexPieces(tuple(np.ascontiguousarray(p) for p in parts), excess, time.perf_counter() - start)
    atomic_write_bytes(path, pieces.to_bytes())
    logger.info("%s: %d convex pieces, cover excess %.2e m, %.1f s", mesh.path.name, len(parts), excess,
                pieces.seconds)
    return pieces
