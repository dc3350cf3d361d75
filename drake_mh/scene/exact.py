"""Exact signed distances of a :class:`drake_mh.scene.Scene`: compiled where Drake is slow or
optimistic, Drake's query for the rest.

Why compiled: reading Drake's answer pair by pair from Python (a ``GetPoseInWorld`` of several
µs per geometry, a Python call per refined pair) cost many times Drake's query itself; one
compiled call per configuration does not (its cost against Drake's query: docs/benchmarks.md).

How distances are computed (:class:`ExactDistances`, one per scene):

* **link geometry vs obstacle** for every link shape :mod:`drake_mh.scene.kernels.exact`
  handles (sphere, capsule, box, cylinder, ellipsoid, convex mesh): one compiled call per
  configuration computes the geometries' world poses from ``q`` (the robot's compiled chain)
  and every pair's exact distance — closed form for sphere/capsule pairs, the golden-section
  axis search of :mod:`drake_mh.scene.segment_distance` for capsule links vs boxes and
  cylinders, the certified GJK of :mod:`drake_mh.scene.kernels.gjk` for the other shapes (Drake's
  GJK was measured up to 16 mm optimistic there). These pairs are filtered out of Drake's
  query in the scene's context (:meth:`ExactDistances.exclude`).
  That call runs in the compiled core ``drake_mh._native`` where it is built (the same
  arithmetic in C++, ``cpp/exact.hpp``: nothing compiled at call time), in the numba kernel
  where it is not or ``DRAKE_MH_COMPILED_CORE=0`` (read when the scene builds its
  :class:`ExactDistances`).
* Where the exact method does not hold — a capsule's axis inside a box or cylinder, or
  overlapping GJK cores — Drake's ``ComputeSignedDistancePairClosestPoints`` is asked for that
  pair and the smaller value kept (Drake's penetration depth).
* **Drake's query** (``ComputeSignedDistancePairwiseClosestPoints``) still answers self pairs
  other than capsule-capsule, and link shapes the kernels do not know (none in the bundled or
  example robots).
* :meth:`ExactDistances.min_distance` builds no pair objects and refines pairs in the order of
  a cheap lower bound (obstacle SDF at the link's bounding-sphere centre minus its radius),
  stopping when the bound reaches the smallest distance found.

Meshes and point clouds: a mesh is one row per convex piece, a ``HULL`` core grown by the
pieces' cover excess (:mod:`drake_mh.geometry.convex_pieces`), for every link shape (spheres
and capsules through their point and segment cores), the nearest piece reported per link
geometry; a point cloud is computed by :mod:`drake_mh.scene.cloud_distance`.

Guarantee: every value is the exact signed distance (to a mesh: to its pieces grown by the
cover excess, which hold the mesh), or (certified GJK) at most
:data:`drake_mh.scene.kernels.gjk.TOLERANCE` below it — never above it where Drake is optimistic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh._support.native import compiled_core
from drake_mh.scene.kernels import exact as X
from drake_mh.scene.kernels import gjk
from drake_mh.scene.segment_distance import primitive_code

__all__ = ["DistancePair", "ExactDistances", "drake_reference", "exclude_from_drake", "link_kinds"]


@dataclass(frozen=True)
class DistancePair:
    """Signed distance between a robot link and an obstacle (or another link).

    Attributes:
        distance: signed distance [m] (negative: penetration depth).
        link: the robot link.
        other: the obstacle name, or the other link for self-distances.
        is_self: whether ``other`` is a robot link.
        p_W_link: closest point on the link, in W [m].
        p_W_other: closest point on the other geometry, in W [m].
        nhat_W: unit normal pointing from ``other`` towards the link, in W.
    """

    distance: float
    link: str
    other: str
    is_self: bool
    p_W_link: np.ndarray
    p_W_other: np.ndarray
    nhat_W: np.ndarray


_new = object.__new__
_set = object.__setattr__


def _pairs(values: np.ndarray, links, others, selfs) -> list[DistancePair]:
    """:class:`DistancePair` objects from rows ``values (n, 10)`` (distance, p_W_link, p_W_other,
    nhat_W) without the frozen dataclass's seven ``object.__setattr__`` calls each."""
    pairs = []
    append = pairs.append
    for d, link, other, is_self, p_link, p_other, nhat in zip(
            values[:, 0].tolist(), links.tolist(), others.tolist(), selfs.tolist(),
            values[:, 1:4], values[:, 4:7], values[:, 7:10]):
        pair = _new(DistancePair)
        _set(pair, "__dict__", {"distance": d, "link": link, "other": other, "is_self": is_self,
                                "p_W_link": p_link, "p_W_other": p_other, "nhat_W": nhat})
        append(pair)
    return pairs


def link_kinds(robot, robot_ids) -> dict:
    """``{geometry id: (kernel link kind, drake_mh shape or None)}`` of robot collision geometries.

    ``LINK_DRAKE`` (Drake's query keeps the pair) for shapes :func:`drake_mh.geometry.shapes.from_drake`
    rejects (half spaces, unreadable meshes) and for bodies off the compiled chain.
    """
    from drake_mh.errors import UnsupportedGeometry
    from drake_mh.geometry.shapes import Capsule, Sphere, from_drake

    inspector = robot.scene_graph.model_inspector()
    anchors = robot.batch.chain.body_anchor
    out = {}
    for gid in robot_ids:
        link = robot.plant.GetBodyFromFrameId(inspector.GetFrameId(gid)).name()
        try:
            shape = from_drake(inspector.GetShape(gid))
        except UnsupportedGeometry:
            shape = None
        if shape is None or link not in anchors:
            out[gid] = (X.LINK_DRAKE, None)
        else:
            out[gid] = (X.LINK_POINT if isinstance(shape, Sphere) else X.LINK_SEGMENT if isinstance(shape, Capsule)
                        else X.LINK_GJK, shape)
    return out


def _link_arrays(shape, kind, X_AG: np.ndarray, anchor: int, hull_start: int):
    """One row of ``g_int`` / ``g_float`` (layout in :mod:`drake_mh.scene.kernels.exact`) and
    the hull vertices it adds."""
    from drake_mh.geometry.shapes import Box, Capsule, ConvexPolytope, Cylinder, Ellipsoid, Sphere

    row_i = np.array([anchor, kind, hull_start, 0, 0], np.int64)
    row_f = np.zeros(20)
    row_f[:9] = X_AG[:3, :3].reshape(-1)
    row_f[9:12] = X_AG[:3, 3]
    vertices = np.zeros((0, 3))
    if isinstance(shape, Sphere):
        row_i[4], row_f[15], row_f[19] = gjk.POINT, shape.radius, shape.radius
    elif isinstance(shape, Capsule):
        row_i[4], row_f[12], row_f[15] = gjk.SEGMENT, 0.5 * shape.length, shape.radius
        row_f[19] = 0.5 * shape.length + shape.radius
    elif isinstance(shape, Box):
        half = 0.5 * np.asarray(shape.size, dtype=float)
        row_i[4], row_f[12:15], row_f[19] = gjk.BOX, half, np.linalg.norm(half)
    elif isinstance(shape, Cylinder):
        row_i[4], row_f[12:14] = gjk.CYLINDER, (shape.radius, 0.5 * shape.length)
        row_f[19] = np.hypot(shape.radius, 0.5 * shape.length)
    elif isinstance(shape, Ellipsoid):
        row_i[4], row_f[12:15], row_f[19] = gjk.ELLIPSOID, (shape.a, shape.b, shape.c), max(shape.a, shape.b, shape.c)
    elif isinstance(shape, ConvexPolytope):
        vertices = np.asarray(shape.vertices, dtype=float)
        centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        row_i[4], row_i[3] = gjk.HULL, len(vertices)
        row_f[16:19], row_f[19] = centre, np.linalg.norm(vertices - centre, axis=1).max()
    return row_i, row_f, vertices


def obstacle_rows(obstacles, vertex_start: int = 0) -> tuple:
    """``(o_int (K, 2), o_float (K, 20), owners (K,), vertices (V, 3))`` of the obstacles
    (layout in :mod:`.kernels.exact`): one row per primitive and per convex piece of a mesh
    (a ``HULL`` core about the piece's centre, its vertices at ``vertex_start ..`` of the
    kernel's vertex array, its margin the pieces' cover excess; the SDF of the lower bound its
    bounding ball), none for a point cloud (:mod:`drake_mh.scene.cloud_distance`); ``owners``
    the index of each row's obstacle."""
    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.geometry.mesh import Mesh
    from drake_mh.geometry.shapes import Capsule, Sphere

    o_int, o_float, owners, hulls = [], [], [], []
    for j, obstacle in enumerate(obstacles):
        shape, R_WO, p_WO = obstacle.shape, obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
        if isinstance(shape, PointCloud):
            continue
        if isinstance(shape, Mesh):
            pieces = convex_pieces(shape)
            for V, (centre, radius, _, _) in zip(pieces.vertices, pieces.kernel_planes):
                row_f = np.zeros(20)
                row_f[:9], row_f[9:12] = R_WO.reshape(-1), R_WO @ centre + p_WO
                row_f[12] = radius  # the bounding ball's SDF: the cheap lower bound
                row_f[15:17] = vertex_start, len(V)
                row_f[18] = pieces.excess
                o_int.append((0, gjk.HULL))
                o_float.append(row_f)
                owners.append(j)
                hulls.append(V - centre)
                vertex_start += len(V)
            continue
        sdf_kind, dims = primitive_code(shape)
        row_f = np.zeros(20)
        row_f[:9], row_f[9:12], row_f[12:15] = R_WO.reshape(-1), p_WO, dims
        if isinstance(shape, Sphere):
            row_i, row_f[18] = (sdf_kind, gjk.POINT), shape.radius
        elif isinstance(shape, Capsule):
            row_i, row_f[15], row_f[18] = (sdf_kind, gjk.SEGMENT), 0.5 * shape.length, shape.radius
        else:  # box: half sizes; cylinder: radius, half length (as the SDF dims)
            row_i, row_f[15:18] = (sdf_kind, gjk.BOX if sdf_kind == 1 else gjk.CYLINDER), dims
        o_int.append(row_i)
        o_float.append(row_f)
        owners.append(j)
    return (np.array(o_int, np.int64).reshape(-1, 2), np.array(o_float, dtype=float).reshape(-1, 20),
            np.array(owners, np.int64), np.concatenate(hulls) if hulls else np.zeros((0, 3)))


class _ObstacleState:
    """What depends on the obstacles: their arrays, names, the output buffers."""

    def __init__(self, exact: ExactDistances, scene):
        from drake_mh.geometry.cloud import PointCloud

        self.key = tuple(scene._ids.values())
        obstacles = list(scene._obstacles.values())
        self.o_int, self.o_float, owners, hulls = obstacle_rows(obstacles, len(exact.vertices))
        self.vertices = np.ascontiguousarray(np.concatenate([exact.vertices, hulls]))
        names = [obstacles[j].name for j in owners]
        self.gids, seen = [], {}  # a mesh's rows: its pieces' geometry ids, in order
        for name in names:
            seen[name] = seen.get(name, -1) + 1
            self.gids.append(scene._ids[name][seen[name]])
        self.names = names
        self.index = {gid: k for k, gid in enumerate(self.gids)}
        self.margin = np.where(self.o_int[:, 1] == gjk.HULL, self.o_float[:, 18], 0.0)  # a piece's cover excess
        self.many_rows = len(set(owners.tolist())) != len(owners)  # a mesh: several rows per obstacle
        self.clouds = [o for o in obstacles if isinstance(o.shape, PointCloud)]
        G, K, S = len(exact.gids), len(names), len(exact.self_pairs)
        n = G * K + S
        self.K = K
        self.out = np.zeros((n, 10))
        self.status = np.zeros(n, np.int64)
        self.need = np.zeros(n, np.int64)
        self.order = np.zeros(n, np.int64)
        # row -> (link, other, is_self)
        self.row_link = np.array([exact.links[i // K] for i in range(G * K)]
                                 + [exact.links[a] for a, _ in exact.self_pairs], dtype=object)
        self.row_other = np.array([names[i % K] for i in range(G * K)]
                                  + [exact.links[b] for _, b in exact.self_pairs], dtype=object)
        self.row_self = np.array([False] * (G * K) + [True] * S, dtype=bool)
        self.query_needed = exact.drake_self or (exact.drake_links and K > 0)
        self.compiled = None  # the compiled core's ExactPairs of these arrays, made on first use


class ExactDistances:
    """Exact distances of one :class:`drake_mh.scene.Scene` (its robot side compiled once).

    Args:
        scene: the scene; its obstacles are re-read whenever their geometry ids change (every
            ``add``, ``move``, ``remove`` registers new ids).
    """

    def __init__(self, scene):
        robot = scene.robot
        self.scene = scene
        self.robot = robot
        inspector = robot.scene_graph.model_inspector()
        plant = robot.plant
        chain = robot.batch.chain
        self.gids = list(scene._robot_ids)
        self.row = {gid: g for g, gid in enumerate(self.gids)}
        self.links = [plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in self.gids]
        rows_i, rows_f, hulls, start = [], [], [], 0
        self.posed = np.array([link in chain.body_anchor for link in self.links])  # kernel computes the pose
        for gid, link in zip(self.gids, self.links):
            kind, shape = scene._link_kinds[gid]
            X_BG = inspector.GetPoseInFrame(gid).GetAsMatrix4()
            anchor, X_AB = chain.body_anchor.get(link, (-1, np.eye(4)))
            X_AG = X_AB @ X_BG
            row_i, row_f, vertices = _link_arrays(shape, kind, X_AG, anchor, start)
            rows_i.append(row_i)
            rows_f.append(row_f)
            hulls.append(vertices)
            start += len(vertices)
        G = len(self.gids)
        self.g_int = np.ascontiguousarray(np.array(rows_i, np.int64).reshape(G, 5))
        self.g_float = np.ascontiguousarray(np.array(rows_f).reshape(G, 20))
        self.vertices = np.ascontiguousarray(np.concatenate(hulls + [np.zeros((1, 3))]))
        self.self_pairs = np.array([(self.row[a], self.row[b]) for a, b in scene._self_capsule_pairs],
                                   np.int64).reshape(-1, 2)
        self.drake_links = bool(np.any(self.g_int[:, 1] == X.LINK_DRAKE))
        self.drake_self = scene.self_collision and self._drake_has_self_pairs()
        self.R_WG = np.zeros((G, 3, 3))
        self.p_WG = np.zeros((G, 3))
        self._chain = robot.batch.chain_arrays
        self._core = compiled_core()
        self._shape = (robot.nq,)
        self._state: _ObstacleState | None = None

    def _drake_has_self_pairs(self) -> bool:
        """Whether some robot-robot pair is left to Drake's query (not filtered)."""
        scene = self.scene
        inspector = scene.robot.scene_graph.get_query_output_port().Eval(scene._sg_context).inspector()
        return any(not inspector.CollisionFiltered(a, b)
                   for i, a in enumerate(self.gids) for b in self.gids[i + 1:])

    def state(self) -> _ObstacleState:
        """The obstacle arrays, rebuilt when the obstacles changed."""
        state = self._state
        if state is None or state.key != tuple(self.scene._ids.values()):
            state = self._state = _ObstacleState(self, self.scene)
        return state

    def _q(self, q) -> np.ndarray:
        if not (type(q) is np.ndarray and q.dtype == np.float64 and q.shape == self._shape and q.flags.c_contiguous):
            q = np.ascontiguousarray(self.robot.check_q(q))
        return q

    def _run(self, q, max_distance: float, min_only: bool):
        state = self.state()
        if self._core is not None:  # the compiled core: the same arrays, checked and held once per state
            if state.compiled is None:
                state.compiled = self._core.ExactPairs(
                    *self._chain, self.g_int, self.g_float, state.vertices, state.o_int, state.o_float,
                    self.self_pairs, gjk.TOLERANCE, self.R_WG, self.p_WG, state.out, state.status, state.need,
                    state.order)
            best, n_need, n_rows = state.compiled(q, max_distance, min_only)
        else:
            best, n_need, n_rows = X.exact_pairs(
                q, *self._chain, self.g_int, self.g_float, state.vertices, state.o_int, state.o_float,
                self.self_pairs, max_distance, min_only, gjk.TOLERANCE, self.R_WG, self.p_WG, state.out, state.status,
                state.need, state.order)
        if n_need < 0:
            self.robot.check_q(q)  # raises, naming the joints
        return state, best, n_need, n_rows

    def _query(self, q):
        scene = self.scene
        self.robot.plant.SetPositions(scene._plant_context, q)
        return self.robot.scene_graph.get_query_output_port().Eval(scene._sg_context)

    def _drake_pair(self, query, state, i):
        """Drake's answer for kernel row i (a link geometry vs an obstacle): ``(distance, p_W_link,
        p_W_other, nhat_W)``."""
        g, k = divmod(i, state.K)
        gid_link, gid_other = self.gids[g], state.gids[k]
        pair = query.ComputeSignedDistancePairClosestPoints(gid_link, gid_other)
        p_A, p_B, nhat = np.asarray(pair.p_ACa), np.asarray(pair.p_BCb), np.asarray(pair.nhat_BA_W)
        if pair.id_A != gid_link:
            p_A, p_B, nhat = p_B, p_A, -nhat
        R_WO, p_WO = state.o_float[k, :9].reshape(3, 3), state.o_float[k, 9:12]
        margin = state.margin[k]  # a piece grown by its cover excess
        return (float(pair.distance) - margin, self.R_WG[g] @ p_A + self.p_WG[g], R_WO @ p_B + p_WO + margin * nhat,
                nhat)

    def min_distance(self, q) -> float:
        """Smallest exact signed distance [m] of ``q (nq,)`` over all pairs (``inf``: no pair)."""
        q = self._q(q)
        state, best, n_need, _ = self._run(q, np.inf, True)
        if n_need or state.query_needed:
            query = self._query(q)
            for i in state.need[:n_need]:
                k = i % state.K
                best = min(best, query.ComputeSignedDistancePairClosestPoints(
                    self.gids[i // state.K], state.gids[k]).distance - state.margin[k])
            if state.query_needed:
                for pair in query.ComputeSignedDistancePairwiseClosestPoints():
                    k = state.index.get(pair.id_B, state.index.get(pair.id_A))
                    best = min(best, pair.distance - (state.margin[k] if k is not None else 0.0))
        if state.clouds:
            from drake_mh.scene.cloud_distance import cloud_rows

            for obstacle in state.clouds:
                rows = cloud_rows(self, state, q, obstacle, best)
                if len(rows):
                    best = min(best, float(rows[:, 1].min()))  # column 0: the geometry
        return float(best)

    def distances(self, q, max_distance: float) -> list[DistancePair]:
        """Every pair within ``max_distance`` [m], closest first (see ``Scene.distances``)."""
        q = self._q(q)
        state, _, n_need, n_rows = self._run(q, max_distance, False)
        if n_need or state.query_needed or state.clouds or state.many_rows:
            return self._distances_with_drake(q, state, n_need, max_distance)
        rows = state.order[:n_rows]
        return _pairs(state.out[rows], state.row_link[rows], state.row_other[rows], state.row_self[rows])

    def _distances_with_drake(self, q, state, n_need: int, max_distance: float) -> list[DistancePair]:
        """:meth:`distances` when Drake answers some pairs (penetration, Drake's query)."""
        out = state.out
        query = self._query(q)
        for i in state.need[:n_need]:
            d, p_link, p_other, nhat = self._drake_pair(query, state, i)
            if d < out[i, 0]:
                out[i, 0], out[i, 1:4], out[i, 4:7], out[i, 7:10] = d, p_link, p_other, nhat
            state.status[i] = X.EXACT
        rows = np.flatnonzero((state.status == X.EXACT) & (out[:, 0] <= max_distance))
        values = out[rows]
        links, others, selfs = state.row_link[rows], state.row_other[rows], state.row_self[rows]
        extra = self._drake_query_pairs(query, state, max_distance) if state.query_needed else []
        if state.clouds:
            from drake_mh.scene.cloud_distance import cloud_rows

            for obstacle in state.clouds:
                found = cloud_rows(self, state, q, obstacle, max_distance, per_geometry=True)
                extra += [(row[1:], self.links[int(row[0])], obstacle.name, False) for row in found]
        if extra:
            values = np.concatenate([values, np.array([e[0] for e in extra])])
            links = np.concatenate([links, np.array([e[1] for e in extra], dtype=object)])
            others = np.concatenate([others, np.array([e[2] for e in extra], dtype=object)])
            selfs = np.concatenate([selfs, np.array([e[3] for e in extra], dtype=bool)])
        order = np.argsort(values[:, 0], kind="stable")
        if state.many_rows:  # a mesh's pieces: the nearest per (link geometry, obstacle)
            seen, keep = set(), []
            for j in order:
                key = (rows[j] // state.K, others[j]) if j < len(rows) and not selfs[j] else j
                if key not in seen:
                    seen.add(key)
                    keep.append(j)
            order = np.asarray(keep, np.int64)
        return _pairs(values[order], links[order], others[order], selfs[order])

    def _drake_query_pairs(self, query, state, max_distance: float) -> list:
        """Drake's pairwise query (self pairs, unknown link shapes): ``[(row (10,), link, other, is_self)]``."""
        out = []
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(float(max_distance)):
            ids = [pair.id_A, pair.id_B]
            points = [np.asarray(pair.p_ACa), np.asarray(pair.p_BCb)]
            nhat = np.asarray(pair.nhat_BA_W)
            if ids[0] not in self.row:  # make the robot side first
                ids.reverse()
                points.reverse()
                nhat = -nhat
            row = np.empty(10)
            row[0] = pair.distance
            for j, (gid, p) in enumerate(zip(ids, points)):
                row[1 + 3 * j:4 + 3 * j] = self._to_world(query, state, gid, p)
            row[7:] = nhat
            k = state.index.get(ids[1])
            if k is not None and state.margin[k]:  # a mesh's piece grown by its cover excess
                row[0] -= state.margin[k]
                row[4:7] += state.margin[k] * nhat
            is_self = ids[1] in self.row
            other = self.links[self.row[ids[1]]] if is_self else state.names[state.index[ids[1]]]
            out.append((row, self.links[self.row[ids[0]]], other, is_self))
        return out

    def _to_world(self, query, state, gid, p_G) -> np.ndarray:
        g = self.row.get(gid)
        if g is not None and self.posed[g]:
            return self.R_WG[g] @ p_G + self.p_WG[g]
        if g is None:
            k = state.index[gid]
            return state.o_float[k, :9].reshape(3, 3) @ p_G + state.o_float[k, 9:12]
        return query.GetPoseInWorld(gid) @ p_G


def exclude_from_drake(scene, obstacle_gid) -> None:
    """Filter every link geometry the kernels handle vs obstacle ``obstacle_gid`` out of Drake's
    query in ``scene``'s context (they are computed by :class:`ExactDistances`; Drake 1.51's
    capsule-capsule query can also hang on collinear axes)."""
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

    kernel_ids = [gid for gid, (kind, _) in scene._link_kinds.items() if kind != X.LINK_DRAKE]
    if kernel_ids:
        scene.robot.scene_graph.collision_filter_manager(scene._sg_context).Apply(
            CollisionFilterDeclaration().ExcludeBetween(GeometrySet([obstacle_gid]), GeometrySet(kernel_ids)))


def drake_reference(scene):
    """Drake's own signed-distance query on ``scene``'s robot and obstacles, set up as a Drake
    user would: a fresh context of the robot's diagram with the obstacles registered in it,
    robot-robot pairs filtered out unless ``scene.self_collision`` (then Drake's default filter
    of adjacent links), and capsule-capsule pairs filtered out (Drake 1.51's query never returns
    on collinear touching axes). A mesh is registered as its convex pieces (Drake ``Convex``
    shapes, not grown by their cover excess); a point cloud is left out (Drake has no such
    shape). The reference for benchmarks and tests: the scene's own context
    no longer asks Drake for the pairs :class:`ExactDistances` computes.

    Returns:
        ``query(q, max_distance=inf) -> list[pydrake SignedDistancePair]``, with attributes
        ``names`` (``{geometry id: link or obstacle name}``), ``plant_context`` and
        ``sg_context`` (for Drake's other queries, e.g. ``HasCollisions``, on the same state).
    """
    from pydrake.geometry import CollisionFilterDeclaration, GeometryInstance, GeometrySet, ProximityProperties
    from pydrake.math import RigidTransform, RotationMatrix

    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.geometry.mesh import Mesh
    from drake_mh.geometry.shapes import Capsule

    robot = scene.robot
    sg, plant = robot.scene_graph, robot.plant
    context = robot.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    sg_context = sg.GetMyMutableContextFromRoot(context)
    manager = sg.collision_filter_manager(sg_context)
    robot_ids = list(scene._robot_ids)
    capsule_links = [gid for gid, (kind, _) in scene._link_kinds.items() if kind == X.LINK_SEGMENT]
    names = dict(zip(scene._exact.gids, scene._exact.links))
    if not scene.self_collision:
        manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_ids)))
    elif capsule_links:
        manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(capsule_links)))
    for name, obstacle in scene.obstacles.items():
        X_WO = RigidTransform(RotationMatrix(obstacle.X_WO[:3, :3]), obstacle.X_WO[:3, 3])
        if isinstance(obstacle.shape, PointCloud):
            continue  # Drake has no point-cloud shape
        shapes = convex_pieces(obstacle.shape).drake_shapes if isinstance(obstacle.shape, Mesh) else (
            (np.zeros(3), obstacle.shape.to_drake()),)
        for centre, shape in shapes:
            instance = GeometryInstance(X_WO @ RigidTransform(centre), shape, f"obstacle::{name}")
            instance.set_proximity_properties(ProximityProperties())
            gid = sg.RegisterGeometry(sg_context, robot.obstacle_source_id, sg.world_frame_id(), instance)
            names[gid] = name
            if isinstance(obstacle.shape, Capsule) and capsule_links:
                manager.Apply(CollisionFilterDeclaration().ExcludeBetween(GeometrySet([gid]),
                                                                          GeometrySet(capsule_links)))
    port = sg.get_query_output_port()

    def query(q, max_distance: float = np.inf):
        plant.SetPositions(plant_context, q)
        return port.Eval(sg_context).ComputeSignedDistancePairwiseClosestPoints(max_distance)

    query.names = names
    query.plant_context, query.sg_context = plant_context, sg_context
    return query
