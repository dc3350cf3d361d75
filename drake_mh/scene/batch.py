"""Batched collision queries on the sphere model: the arrays the compiled kernels read.

:class:`CollisionModel` flattens what :mod:`drake_mh.scene.kernels.collision` needs from a
:class:`drake_mh.scene.Scene`:

* the robot's kinematic chain (from :class:`drake_mh.kinematics.BatchKinematics`);
* its :class:`drake_mh.geometry.spheres.SphereModel`, grouped per link, each link with a *bounding
  sphere* that contains all of the link's spheres (centre: the middle of the centres' bounding
  box; radius: the farthest sphere surface from it), and a *bounding capsule* (tighter for long
  links: the pairs' second test);
* the obstacles as arrays (kind, ``R_WO``, ``p_WO``, half sizes);
* the link pairs checked for self-collision: every pair of links with collision geometry that
  Drake's collision filter of the scene does not exclude (Drake filters links connected by a
  joint and links welded together; ``Scene(ignore_link_pairs=...)`` adds more), with floor
  tables for the pairs that one or two joints move (:mod:`drake_mh.scene.pair_table`);

and, per sphere and per link pair, how far it can move when the configuration moves
(:meth:`CollisionModel.reach`), which the segment certificate needs.
"""

from __future__ import annotations

import functools

import numpy as np

from drake_mh.scene.compiled_check import compiled_core
from drake_mh.scene.kernels import collision as K
from drake_mh.scene.kernels import entry as E
from drake_mh.scene.kernels.packing import pack
from drake_mh.scene.pair_table import empty_tables
from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere


def obstacle_arrays(obstacles) -> tuple:
    """``(kinds (K,), R_WO (K, 3, 3), p_WO (K, 3), v_WO (K, 3), dims (D, 3))`` of the obstacles
    as the kernels read them (``v_WO`` zero: the kernels' per-lane displacement, set by segment
    checks). A mesh is one kernel obstacle per convex piece (:func:`obstacle_owners` maps them
    back), a point cloud one; ``dims`` is the shape table of :mod:`.kernels.pieces`: the
    obstacles' rows, then the pieces' planes and the clouds' grids and trees
    (:mod:`.kernels.cloud`)."""
    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.scene.cloud_grid import cloud_entry
    from drake_mh.geometry.mesh import Mesh
    from drake_mh.scene.kernels.pieces import CLOUD, CONVEX

    rows = []  # (kind, R_WO, p_WO, dims row, data rows or None)
    for obstacle in obstacles:
        shape, R, p = obstacle.shape, obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
        if isinstance(shape, Mesh):
            for centre, radius, normals, offsets in convex_pieces(shape).kernel_planes:
                M = len(offsets)
                table = np.zeros((M + (M + 2) // 3, 3))
                table[:M] = normals @ R.T  # in W
                table[M:].reshape(-1)[:M] = offsets
                rows.append((CONVEX, np.eye(3), R @ centre + p, (M, radius), table))
        elif isinstance(shape, PointCloud):
            rows.append(cloud_entry(shape, R, p, CLOUD))
        elif isinstance(shape, Sphere):
            rows.append((K.SPHERE, R, p, (shape.radius, 0.0, 0.0), None))
        elif isinstance(shape, Box):
            rows.append((K.BOX, R, p, tuple(0.5 * np.asarray(shape.size)), None))
        elif isinstance(shape, Cylinder):
            rows.append((K.CYLINDER, R, p, (shape.radius, 0.5 * shape.length, 0.0), None))
        elif isinstance(shape, Capsule):
            rows.append((K.CAPSULE, R, p, (shape.radius, 0.5 * shape.length, 0.0), None))
        else:  # Scene.add accepts only these
            raise TypeError(f"no batched distance for obstacle shape {type(shape).__name__}")
    n = len(rows)
    kinds = np.array([r[0] for r in rows], np.int64)
    R_WO, p_WO = np.empty((n, 3, 3)), np.empty((n, 3))
    tables, start = [np.zeros((n, 3))], n
    for k, (_, R, p, row, table) in enumerate(rows):
        R_WO[k], p_WO[k] = R, p
        if table is None:
            tables[0][k] = row
        else:  # (start of its data, count, bounding radius)
            tables[0][k] = (start, row[0], row[1])
            tables.append(table)
            start += len(table)
    return kinds, R_WO, p_WO, np.zeros((n, 3)), np.ascontiguousarray(np.concatenate(tables))


def obstacle_owners(obstacles) -> np.ndarray:
    """``(K,)`` int64: for each kernel obstacle of :func:`obstacle_arrays`, the index of the
    obstacle it belongs to (a mesh's pieces share their mesh's)."""
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.geometry.mesh import Mesh

    return np.array([i for i, o in enumerate(obstacles)
                     for _ in range(len(convex_pieces(o.shape)) if isinstance(o.shape, Mesh) else 1)], np.int64)


def bounding_radii(obstacles: tuple) -> np.ndarray:
    """``(K,)`` radius of the smallest ``p_WO``-centred sphere containing each obstacle [m]."""
    kinds, _, _, _, table = obstacles
    dims = table[:len(kinds)]
    radii = np.where(kinds == K.BOX, np.linalg.norm(dims, axis=1), dims[:, 0])
    radii = np.where(kinds == K.CYLINDER, np.hypot(dims[:, 0], dims[:, 1]), radii)
    radii = np.where(kinds >= K.CONVEX, dims[:, 2], radii)
    return np.ascontiguousarray(np.where(kinds == K.CAPSULE, dims[:, 0] + dims[:, 1], radii))


GROUP_SIZE = 16
"""Most spheres in a group (:func:`sphere_groups`)."""


def sphere_groups(centres: np.ndarray, size: int = GROUP_SIZE) -> list:
    """Index arrays that split ``centres (n, 3)`` into groups of at most ``size`` neighbours:
    halves at the median along the longest side of the bounding box, recursively
    (deterministic). A group's bounding sphere lets a near link's spheres be tested against an
    obstacle a group at a time."""
    parts, todo = [], [np.arange(len(centres))]
    while todo:
        idx = todo.pop()
        if len(idx) <= size:
            parts.append(idx)
            continue
        c = centres[idx]
        ranked = idx[np.argsort(c[:, int(np.argmax(np.ptp(c, axis=0)))], kind="stable")]
        half = len(ranked) // 2
        todo += [ranked[half:], ranked[:half]]
    return parts


def bounding_spheres(offsets: np.ndarray, radii: np.ndarray, start: np.ndarray) -> tuple:
    """``(centre (R, 3), radius (R,))``: per range ``start[r] .. start[r + 1] - 1`` of spheres
    (centres ``offsets`` in one frame) a sphere that contains them: centred in the middle of the
    centres' bounding box, out to the farthest sphere surface."""
    R = len(start) - 1
    centre, radius = np.empty((R, 3)), np.empty(R)
    for r in range(R):
        c = offsets[start[r]:start[r + 1]]
        centre[r] = 0.5 * (c.min(axis=0) + c.max(axis=0))
        radius[r] = np.max(np.linalg.norm(c - centre[r], axis=1) + radii[start[r]:start[r + 1]])
    return centre, radius


def bounding_capsules(offsets: np.ndarray, radii: np.ndarray, start: np.ndarray) -> np.ndarray:
    """``(G, 7)``: per link (spheres ``start[g] .. start[g + 1] - 1``, centres ``offsets`` in the
    link's frame) a capsule that contains all of its spheres: axis ends (6) and radius.

    The axis is the centres' principal direction through their mean; of 21 lengths (the
    centres' whole projected extent down to a point) the one of least volume is kept; the radius
    is then the farthest sphere surface from that segment, so containment holds exactly.
    """
    out = np.empty((len(start) - 1, 7))
    for g in range(len(start) - 1):
        c, r = offsets[start[g]:start[g + 1]], radii[start[g]:start[g + 1]]
        m = c.mean(axis=0)
        u = np.linalg.svd(c - m)[2][0] if len(c) > 1 else np.array([0.0, 0.0, 1.0])
        t = (c - m) @ u
        best = None
        for shrink in np.linspace(0.0, 1.0, 21):
            half = 0.5 * shrink * (t.max() - t.min())
            lo, hi = t.min() + half, t.max() - half
            radius = float(np.max(np.linalg.norm(c - (m + np.clip(t, lo, hi)[:, None] * u), axis=1) + r))
            volume = np.pi * radius ** 2 * (hi - lo) + 4.0 / 3.0 * np.pi * radius ** 3
            if best is None or volume < best[0]:
                best = (volume, np.concatenate([m + lo * u, m + hi * u, [radius]]))
        out[g] = best[1]
    return out


class CollisionModel:
    """The sphere model of a scene's robot, grouped per link for the compiled kernels.

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        model: its :class:`drake_mh.geometry.spheres.SphereModel`.
        self_pairs: ``[(link_a, link_b)]`` link pairs to check for self-collision.
    """

    def __init__(self, robot, model, self_pairs=(), pair_tables: bool = True):
        batch = robot.batch
        self.robot = robot
        self.sphere_model = model
        links = np.asarray(model.links)
        self.link_names = tuple(dict.fromkeys(model.links))  # order of first appearance
        order, sizes, g_ustart = [], [], [0]
        for name in self.link_names:  # each link's spheres in groups of neighbours
            ids = np.flatnonzero(links == name)
            for part in sphere_groups(model.centres_B[ids]):
                order.extend(ids[part])
                sizes.append(len(part))
            g_ustart.append(len(sizes))
        order = np.asarray(order, np.int64)
        self.sphere_order = order  # kernel sphere i is model sphere order[i]
        anchors, offsets = batch.compile_points(list(links[order]), model.centres_B[order])
        radii = np.ascontiguousarray(model.radii[order])
        counts = [int(np.sum(links == name)) for name in self.link_names]
        start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        g_anchor = anchors[start[:-1]]
        g_offset, g_radius = bounding_spheres(offsets, radii, start)
        self.sphere_anchor = anchors
        self.model_arrays = (g_anchor, g_offset, g_radius, start, offsets, radii)
        self.capsules = bounding_capsules(offsets, radii, start)
        u_start = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.group_arrays = (np.asarray(g_ustart, np.int64), u_start) + bounding_spheres(offsets, radii, u_start)
        self.chain_arrays = batch.chain_arrays
        index = {name: g for g, name in enumerate(self.link_names)}
        pairs = sorted({tuple(sorted((index[a], index[b]))) for a, b in self_pairs
                        if a in index and b in index and a != b})
        self.self_pairs = tuple((self.link_names[a], self.link_names[b]) for a, b in pairs)
        self.pair_index = (np.array([a for a, _ in pairs], np.int64), np.array([b for _, b in pairs], np.int64))
        self._use_tables = pair_tables
        self._compiled = {}  # with pairs or not -> (obstacles, drake_mh._native.Clearances): compiled_clearances
        self._packs = {}  # id(pairs) -> (obstacles, pairs, (ints, floats)): packed

    @functools.cached_property
    def pair_arrays(self) -> tuple:
        """``(pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset,
        u_radius)``: what the kernels read beyond the chain, the spheres and the obstacles: the
        checked link pairs (rows of the links), their floor tables
        (:func:`drake_mh.scene.pair_table.pair_tables`; built on first use, a second or two per
        meshed arm, then cached on disk), the links' bounding capsules
        (:func:`bounding_capsules`) and the links' sphere groups (:attr:`group_arrays`: link
        ``g`` holds groups ``g_ustart[g] .. g_ustart[g + 1] - 1``, group ``u`` the spheres
        ``u_start[u] .. u_start[u + 1] - 1`` inside the sphere ``(u_offset[u], u_radius[u])``)."""
        from drake_mh.scene.pair_table import pair_tables

        tables = pair_tables(self) if self._use_tables else empty_tables(self.num_pairs)
        return self.pair_index + tables + (self.capsules,) + self.group_arrays

    @functools.cached_property
    def no_pair_arrays(self) -> tuple:
        """:attr:`pair_arrays` without link pairs (and no tables to build): for the queries per
        obstacle."""
        return (np.zeros(0, np.int64), np.zeros(0, np.int64), *empty_tables(), self.capsules, *self.group_arrays)

    @property
    def num_links(self) -> int:
        return len(self.link_names)

    @property
    def num_pairs(self) -> int:
        return len(self.self_pairs)

    def _kernel_args(self) -> tuple:
        return self.chain_arrays + self.model_arrays

    @functools.cached_property
    def reach_balls(self) -> tuple:
        """``(centre_W (G, 3), radius (G,))``: a ball fixed in the world that holds the centre of
        each link's bounding sphere in every configuration. Its centre is the origin of the link's
        root frame (the first moving frame of its chain, fixed in the world), its radius the
        length of the chain from there: the offsets between the frames' origins, the largest
        travel of the prismatic joints on the way (a root that is prismatic included) and the
        bounding centre's offset (a link fixed to the world: its centre, radius 0)."""
        chain = self.robot.batch.chain
        parent, Kp, kind, qidx = chain.parent, chain.K[:, :3, 3], chain.kind, chain.qidx
        travel = np.maximum(np.abs(self.robot.lower), np.abs(self.robot.upper))
        g_anchor, g_offset = self.model_arrays[:2]
        centre, radius = np.array(g_offset, dtype=float), np.zeros(len(g_anchor))
        for g, a in enumerate(g_anchor):
            if a < 0:
                continue  # fixed to the world: g_offset is its centre
            length, k = float(np.linalg.norm(g_offset[g])), a
            while True:
                if kind[k] != 0:
                    length += travel[qidx[k]]
                if parent[k] < 0:
                    break
                length += float(np.linalg.norm(Kp[k]))  # from the parent's origin to k's
                k = parent[k]
            centre[g], radius[g] = Kp[k], length
        return centre, radius

    def static_gaps(self, obstacles: tuple) -> np.ndarray:
        """``(G, K)``: for each link and obstacle a distance [m] that their bounding spheres keep
        in every configuration (the obstacle where it is): the distance from the link's
        :attr:`reach_balls` to the obstacle's bounding sphere, less 1 nm for round-off. The
        kernels skip a pair whose gap keeps the clearance asked (25-55 % of the pairs of the
        MotionBenchMaker scenes: the links near the base never reach most boards)."""
        centre, radius = self.reach_balls
        p_WO = np.asarray(obstacles[2], dtype=float).reshape(-1, 3)
        g_radius = self.model_arrays[2]
        gap = (np.linalg.norm(centre[:, None, :] - p_WO[None, :, :], axis=2) - radius[:, None] - g_radius[:, None]
               - bounding_radii(obstacles)[None, :] - 1e-9)
        return np.ascontiguousarray(gap)

    def packed(self, obstacles: tuple, pairs: tuple) -> tuple:
        """``(ints, floats)``: :func:`.kernels.packing.pack` of the chain, the spheres, ``obstacles``
        (:func:`obstacle_arrays`; their bounding radii and :meth:`static_gaps`) and ``pairs``
        (:attr:`pair_arrays` or :attr:`no_pair_arrays`). The last buffers per ``pairs`` are kept
        for the same ``obstacles`` tuple (the planner's binding, the batched check and the segment
        certificates of a new scene share one packing); callers only read them."""
        cached = self._packs.get(id(pairs))
        if cached is not None and cached[0] is obstacles and cached[1] is pairs:
            return cached[2]
        kinds, R_WO, p_WO, _, dims = obstacles
        buffers = pack(*self._kernel_args(), kinds, R_WO, p_WO, dims, bounding_radii(obstacles),
                       self.static_gaps(obstacles), *pairs)
        self._packs[id(pairs)] = (obstacles, pairs, buffers)
        return buffers

    def free_function(self, obstacles: tuple):
        """``f(Q (N, nq), clearance, self_clearance) -> (N,) bool`` against ``obstacles`` (None if
        ``Q`` is not finite): :func:`.kernels.collision.collision_free` with every array packed
        and bound once (a call from Python then costs the kernel plus about a microsecond).
        ``Q`` must be a C-contiguous float64 array (compiled for that layout only), the
        clearances Python floats >= 0: the caller checks them.

        ``f.make_one()`` returns ``(entry, buffer)``: ``entry(q (nq,) float64, clearance,
        self_clearance, buffer) -> 1 / 0 / -1 / -2`` (free / not / not finite / a clearance not in
        [0, inf)) checks one configuration (:func:`.kernels.entry.collision_free_one`)
        through the compiled entry point of its one signature: no type dispatch, no allocation
        (about 0.3 µs in the kernel and 0.15 µs of call). ``q`` must be a float64 array of shape
        ``(nq,)`` (any strides), the clearances Python floats: the caller checks those types
        (numba's entry point does not check an array's dtype).
        """
        ints, floats = self.packed(obstacles, self.pair_arrays)
        kernel, empty, boolean = E.collision_free_packed, np.empty, np.bool_

        def free(Q, clearance, self_clearance):
            out = empty(Q.shape[0], boolean)
            # squared tests need a positive clearance: 1e-12 m stands for "touching is a collision"
            if not kernel(Q, max(clearance, 1e-12), max(self_clearance, 1e-12), ints, floats, out):
                return None  # a NaN or an infinity in Q
            return out

        def make_one():  # compiled on first need (about 7 s from an empty numba cache)
            return E.one_entry_point(), E.one_buffer(ints, floats)

        free.make_one = make_one
        return free

    def free(self, Q: np.ndarray, obstacles: tuple, clearance: float, self_clearance: float) -> np.ndarray:
        """``(N,)`` bool: :func:`.kernels.collision.collision_free` of ``Q (N, nq)``."""
        Q = np.ascontiguousarray(Q, dtype=float)
        out = self.free_function(obstacles)(Q, float(clearance), float(self_clearance))
        if out is None:
            raise ValueError("configurations must be finite")  # Scene checks them first
        return out

    def compiled_clearances(self, obstacles: tuple, pairs: bool):
        """The compiled core's ``drake_mh._native.Clearances`` of this model against ``obstacles``
        (:func:`obstacle_arrays`), with the checked link pairs (``pairs``) or without, built once
        per obstacles tuple (a new tuple, as a scene makes after add/move/remove, builds anew);
        None where the core is not built or ``DRAKE_MH_COMPILED_CORE=0``
        (:func:`drake_mh.scene.compiled_check.compiled_core`). Its ``values`` are
        :func:`.kernels.collision.link_clearances`', its ``certify_segments`` the verdicts of
        :func:`.kernels.segments.certify_segments` (the same to round-off: docs/native.md)."""
        core = compiled_core()
        if core is None:
            return None
        cached = self._compiled.get(pairs)
        if cached is not None and cached[0] is obstacles:
            return cached[1]
        ints, floats = self.packed(obstacles, self.pair_arrays if pairs else self.no_pair_arrays)
        compiled = core.Clearances(ints, floats)
        self._compiled[pairs] = (obstacles, compiled)
        return compiled

    def obstacle_clearance_function(self, obstacles: tuple):
        """``f(Q (N, nq), overall=False) -> (N, K)`` clearance per obstacle, or ``(N, 1)`` the
        smallest over them with ``overall`` (None if ``Q`` is not finite): :meth:`clearances`
        with ``per_obstacle`` for the obstacles where they are, every array packed and bound once
        (the compiled core's :meth:`compiled_clearances` where it is built, else
        :func:`.kernels.entry.obstacle_clearances_packed`). ``Q`` must be a C-contiguous
        float64 array: the caller checks it."""
        v_WO = np.ascontiguousarray(obstacles[3], dtype=float).reshape(-1, 3)
        # per obstacle the link pairs are not read: the instance of the segment certificates serves
        compiled = self.compiled_clearances(obstacles, pairs=True)
        if compiled is not None:
            values, none, no_pairs = compiled.values, np.zeros(0), np.zeros(len(self.pair_arrays[0]))

            def compiled_clearance(Q, overall=False):  # tau empty: the obstacles where they are
                return values(Q, none, np.inf, no_pairs, K.OVERALL if overall else K.PER_OBSTACLE, v_WO)

            return compiled_clearance
        ints, floats = self.packed(obstacles, self.no_pair_arrays)
        kernel, empty, K_obstacles = E.obstacle_clearances_packed, np.empty, len(obstacles[0])

        def clearance(Q, overall=False):
            out = empty((Q.shape[0], 1 if overall else K_obstacles))
            return out if kernel(Q, K.OVERALL if overall else K.PER_OBSTACLE, ints, floats, v_WO, out) else None

        return clearance

    def clearances(self, QT: np.ndarray, obstacles: tuple, per_obstacle: bool, fine_below: float = np.inf,
                   tau=None) -> np.ndarray:
        """:func:`.kernels.collision.link_clearances` of ``QT (nq, N)``: ``(N, K)`` per obstacle,
        or ``(N, G + P)`` per link and link pair."""
        N = QT.shape[1]
        width = len(obstacles[0]) if per_obstacle else self.num_links + self.num_pairs
        tau = np.zeros(N) if tau is None else np.ascontiguousarray(tau, dtype=float)
        pairs = self.no_pair_arrays if per_obstacle else self.pair_arrays
        pair_fine = np.full(len(pairs[0]), float(fine_below))
        mode = K.PER_OBSTACLE if per_obstacle else K.PER_LINK
        compiled = self.compiled_clearances(obstacles, pairs=True)  # per obstacle the pairs are not read
        if compiled is not None:
            fine_pairs = np.full(len(self.pair_arrays[0]), float(fine_below))
            out = compiled.values(np.ascontiguousarray(QT.T, dtype=float), tau, float(fine_below), fine_pairs, mode,
                                  np.ascontiguousarray(obstacles[3], dtype=float).reshape(-1, 3))
            if out is not None:
                return out  # (not finite: the kernel's values, as before)
        out = np.empty((N, width))
        K.link_clearances(QT, tau, float(fine_below), pair_fine, mode, *self._kernel_args(), *obstacles,
                          *pairs, out)
        return out

    @functools.cached_property
    def sphere_reach(self) -> np.ndarray:
        """``(S, nq)`` per sphere (kernel order): a bound on the distance of its centre from
        joint j's axis over every configuration (revolute: the centre moves at most
        ``reach · |Δq_j|``), 1 for a prismatic joint on its path, 0 for joints not on its path.
        The bound is the length of the chain from the joint's origin to the centre: the sum of
        the constant offsets between them plus the largest travel of the prismatic joints
        between them."""
        chain = self.robot.batch.chain
        parent, Kp = chain.parent, chain.K[:, :3, 3]
        lower, upper = self.robot.lower, self.robot.upper
        travel = np.maximum(np.abs(lower), np.abs(upper))
        nq = self.robot.nq

        s_offset = self.model_arrays[4]
        anchors = np.asarray(self.sphere_anchor, dtype=np.int64)
        out = np.zeros((len(anchors), nq))
        link = [float(np.linalg.norm(Kp[k])) for k in range(len(parent))]  # from the parent's origin to k's
        for anchor in np.unique(anchors):  # every sphere of one anchor at once, up its chain
            mine = np.flatnonzero(anchors == anchor)
            length = np.array([float(np.linalg.norm(o)) for o in s_offset[mine]])  # anchor's origin to the centre
            k = int(anchor)
            while k >= 0:
                j = chain.qidx[k]
                if chain.kind[k] == 0:
                    out[mine, j] += length
                else:
                    out[mine, j] += 1.0
                    length = length + travel[j]
                length = length + link[k]
                k = parent[k]
        return out

    @functools.cached_property
    def reach(self) -> np.ndarray:
        """``(G + P, nq)``: how far [m] the geometry behind each constraint value can move per
        unit of joint j's motion (the Lipschitz constants of :mod:`.kernels.segments`).

        Rows ``0..G-1`` (links): the elementwise largest :attr:`sphere_reach` row of the link's
        spheres: the link's value (smallest sphere clearance) changes no faster than its
        fastest sphere moves.

        Rows ``G..G+P-1`` (link pairs): the elementwise largest sphere row of each link, summed,
        over the joints that move one link relative to the other (a joint that carries both
        links rotates or translates their difference vector rigidly: its length, and so the
        pair's distance, does not change).
        """
        chain = self.robot.batch.chain
        nq = self.robot.nq
        g_anchor, _, _, start, _, _ = self.model_arrays
        sphere_rows = self.sphere_reach
        group_rows = [np.max(sphere_rows[start[g]:start[g + 1]], axis=0) for g in range(len(g_anchor))]
        rows = list(group_rows)
        ancestors = chain.ancestors
        pair_a, pair_b = self.pair_index
        for ga, gb in zip(pair_a, pair_b):
            shared = np.zeros(nq, bool)
            aa, ab = g_anchor[ga], g_anchor[gb]
            if aa >= 0 and ab >= 0:
                common = ancestors[aa] & ancestors[ab]
                shared[chain.qidx[np.flatnonzero(common)]] = True
            r = group_rows[ga] + group_rows[gb]
            r[shared] = 0.0
            rows.append(r)
        return np.asarray(rows).reshape(-1, nq)
