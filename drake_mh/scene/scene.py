"""Obstacles around a robot, with exact distances and batched conservative ones.

A :class:`Scene` owns its own Drake context of the robot's diagram. Obstacles (primitives,
meshes and point clouds, each at a pose with an optional linear velocity) are registered *in
that context* as anchored geometry, so they are added, moved and removed without rebuilding the
diagram; the robot's self-collision filter lives there too (:mod:`drake_mh.scene.self_filter`).
Exact signed distances come from :mod:`drake_mh.scene.exact` (closed forms, segment searches
and a certified GJK where Drake's was measured optimistic; Drake's query for the other pairs).

For populations, :meth:`Scene.batch_min_distance` uses the robot's
:class:`drake_mh.geometry.spheres.SphereModel`: with ``d`` the exact distance and ``m`` the
model's, ``m <= d`` everywhere, penetration included (:mod:`drake_mh.scene.penetration`), and
``d - bound <= m`` where ``d >= 0`` (:mod:`drake_mh.geometry.spheres`). A robot without
collision geometry has no clearance: a query that needs one raises
:class:`drake_mh.errors.SceneError` instead of answering ``inf``.
"""

from __future__ import annotations

import functools

import numpy as np

from drake_mh.errors import SceneError, UnknownObstacle
from drake_mh.scene.exact import DistancePair, ExactDistances, exclude_from_drake, link_kinds
from drake_mh.geometry.cloud import PointCloud
from drake_mh.geometry.convex_pieces import convex_pieces
from drake_mh.geometry.mesh import Mesh
from drake_mh.geometry.shapes import Box, Capsule, Cylinder, Sphere, as_shape
from drake_mh.geometry.spheres import DEFAULT_TOLERANCE, SphereModel
from drake_mh.scene import compiled_check
from drake_mh.scene.obstacle import Obstacle, rotation_rpy, vector3
from drake_mh.scene.self_filter import filter_self_pairs

__all__ = ["Scene", "Obstacle", "DistancePair", "Sphere", "Box", "Cylinder", "Capsule", "Mesh", "PointCloud"]

_F8, _NDARRAY, _INF = np.dtype(np.float64), np.ndarray, float("inf")  # Scene.collision_free's fast paths


@functools.cache
def _module(name: str):
    """``drake_mh.scene.<name>`` (``segments``, ``penetration``), imported on first use (segments
    loads the segment kernels): a ``from ... import`` in a method costs about 0.7 µs a call, 15 %
    of a short segment's check."""
    import importlib

    return importlib.import_module(f"drake_mh.scene.{name}")


class Scene:
    """Obstacles around a :class:`drake_mh.robot.Robot` and distance queries.

    Args:
        robot: the robot.
        self_collision: also report robot link vs link distances (adjacent links excluded by
            Drake; add more pairs with ``ignore_link_pairs``). Link pairs that are *always
            close* — never more than 1 cm apart under the sphere model anywhere in the joint
            limits, like the capsule Panda's link1-link3 (0.9 mm) — are left out too, listed in
            :attr:`always_close_pairs` and logged (rule: :mod:`drake_mh.scene.always_close`).
        ignore_link_pairs: extra ``(link_a, link_b)`` pairs to exclude from self-distances.
        sphere_tolerance: covering tolerance of the sphere model [m].
        keep_always_close: check the always-close pairs as well (default False: with them, no
            configuration of some robots is certified free of self-collision).
    """

    def __init__(self, robot, self_collision: bool = False, ignore_link_pairs=(),
                 sphere_tolerance: float = DEFAULT_TOLERANCE, keep_always_close: bool = False):
        from pydrake.geometry import Role

        from drake_mh.robot import Robot

        if not isinstance(robot, Robot):
            raise SceneError(f"Scene needs a drake_mh Robot (drake_mh.load_robot(...)), got {type(robot).__name__}")
        self.robot = robot
        self.self_collision = bool(self_collision)
        self._sphere_tolerance = sphere_tolerance
        self._context = robot.diagram.CreateDefaultContext()
        self._plant_context = robot.plant.GetMyMutableContextFromRoot(self._context)
        self._sg_context = robot.scene_graph.GetMyMutableContextFromRoot(self._context)
        self._obstacles: dict[str, Obstacle] = {}
        self._ids: dict[str, object] = {}
        self._obstacle_arrays = None  # the obstacles as the compiled kernels read them (batch.py)
        self._free_function = None
        self._free_one = None  # its one-configuration entry and buffer (batch.CollisionModel.free_function)
        self._clearance_function = None  # batch_obstacle_distances' (batch.CollisionModel.obstacle_clearance_function)
        self._planner_bindings: dict = {}  # what planners bound to these obstacles (planner_binding)
        self._polytopes = None  # the obstacles' polytopes for its penetration correction (penetration.py)
        self._owners = None  # the obstacle of each kernel obstacle (a mesh has one per piece)
        self._q_shape, self._nq = (robot.nq,), robot.nq
        inspector = robot.scene_graph.model_inspector()
        self._robot_ids = [g for g in inspector.GetAllGeometryIds(Role.kProximity)
                           if inspector.GetFrameId(g) != inspector.world_frame_id()]
        self._self_link_pairs, self._always_close, self._self_capsule_pairs = filter_self_pairs(
            robot, self._sg_context, self._robot_ids, self.self_collision, ignore_link_pairs, keep_always_close,
            lambda: self.sphere_model, lambda: self._capsule_links)

    @property
    def always_close_pairs(self) -> tuple:
        """``((link_a, link_b), ...)`` left out of self-collision as always close (empty without
        ``self_collision`` or with ``keep_always_close=True``; :mod:`drake_mh.scene.always_close`)."""
        return self._always_close

    @property
    def self_link_pairs(self) -> tuple:
        """``((link_a, link_b), ...)`` checked for self-collision (empty without ``self_collision``)."""
        return tuple(self._self_link_pairs)

    # --- obstacles ----------------------------------------------------------------------

    @property
    def obstacles(self) -> dict[str, Obstacle]:
        """The obstacles by name (a copy)."""
        return dict(self._obstacles)

    def add(self, name: str, shape, position=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0),
            velocity=(0.0, 0.0, 0.0)) -> Obstacle:
        """Add an obstacle.

        Args:
            name: unique name.
            shape: :class:`Sphere`, :class:`Box`, :class:`Cylinder`, :class:`Capsule`,
                :class:`Mesh` (checked as its convex pieces grown by their cover excess:
                :mod:`drake_mh.geometry.convex_pieces`; a new non-convex mesh is decomposed
                here, seconds to a minute, then cached) or :class:`PointCloud` (the union of
                its balls), or a ``pydrake.geometry`` primitive.
            position: ``p_WO (3,)`` [m] of the obstacle's frame (a mesh's and a cloud's
                coordinates are in that frame).
            rpy: roll-pitch-yaw of the obstacle frame [rad].
            velocity: linear velocity ``(3,)`` [m/s] used by :meth:`step` and by velocity-aware
                planners (ESM).

        Raises:
            SceneError: duplicate name, bad shape or numbers (nothing is changed).
        """
        if not isinstance(name, str) or not name:
            raise SceneError(f"obstacle name must be a non-empty string, got {name!r}")
        if name in self._obstacles:
            raise SceneError(f"an obstacle named {name!r} already exists; use move() or another name")
        if isinstance(shape, Mesh):
            convex_pieces(shape)  # decomposed (or read from the cache) before anything is registered
        elif not isinstance(shape, PointCloud):
            shape = as_shape(shape)
        X_WO = np.eye(4)
        X_WO[:3, :3] = rotation_rpy(rpy)
        X_WO[:3, 3] = vector3(position, "position [m]")
        velocity_W = vector3(velocity, "velocity [m/s]")  # every check before anything is registered
        self._ids[name] = self._register(name, shape, X_WO)
        obstacle = Obstacle(name, shape, X_WO, velocity_W)
        self._obstacles[name] = obstacle
        self._obstacles_changed()
        return obstacle

    def _register(self, name: str, shape, X_WO: np.ndarray) -> tuple:
        """Register ``shape`` at ``X_WO`` as anchored proximity geometry in this scene's context:
        the geometry ids, one per primitive, one per convex piece of a mesh (Drake ``Convex``
        shapes posed at the piece's centre, not grown by the cover excess), none for a point
        cloud (Drake has no such shape: :mod:`drake_mh.scene.cloud_distance` computes its
        distances)."""
        from pydrake.geometry import GeometryInstance, ProximityProperties
        from pydrake.math import RigidTransform, RotationMatrix

        X = RigidTransform(RotationMatrix(X_WO[:3, :3]), X_WO[:3, 3])
        if isinstance(shape, PointCloud):
            return ()
        drake_shapes = convex_pieces(shape).drake_shapes if isinstance(shape, Mesh) else (
            (np.zeros(3), shape.to_drake()),)
        sg = self.robot.scene_graph
        gids = []
        try:
            for i, (centre, drake_shape) in enumerate(drake_shapes):
                label = f"obstacle::{name}" + (f"::piece{i}" if isinstance(shape, Mesh) else "")
                instance = GeometryInstance(X @ RigidTransform(centre), drake_shape, label)
                instance.set_proximity_properties(ProximityProperties())
                gids.append(sg.RegisterGeometry(self._sg_context, self.robot.obstacle_source_id, sg.world_frame_id(),
                                                instance))
                # the link geometries drake_mh.scene.exact computes (sphere, capsule, box, cylinder,
                # ellipsoid, convex mesh) leave Drake's query against obstacles: Drake 1.51's GJK is
                # optimistic there (up to 16 mm), its capsule-capsule query never returns on collinear
                # touching axes, and its Python pair objects cost more than the compiled kernel
                exclude_from_drake(self, gids[-1])
        except BaseException:
            self._unregister(tuple(gids))
            raise
        return tuple(gids)

    def _unregister(self, gids: tuple) -> None:
        for gid in gids:
            self.robot.scene_graph.RemoveGeometry(self._sg_context, self.robot.obstacle_source_id, gid)

    @functools.cached_property
    def _capsule_links(self) -> dict:
        """``{geometry id: Capsule}`` of the robot's capsule collision geometries."""
        from drake_mh.geometry.shapes import from_drake

        inspector = self.robot.scene_graph.model_inspector()
        out = {}
        for gid in self._robot_ids:
            shape = inspector.GetShape(gid)
            if type(shape).__name__ == "Capsule":
                out[gid] = from_drake(shape)
        return out

    @functools.cached_property
    def _link_kinds(self) -> dict:
        """``{geometry id: (kernel link kind, shape)}`` (:func:`drake_mh.scene.exact.link_kinds`)."""
        return link_kinds(self.robot, self._robot_ids)

    @functools.cached_property
    def _exact(self) -> ExactDistances:
        """The compiled exact-distance layout of this scene (:class:`drake_mh.scene.exact.ExactDistances`)."""
        return ExactDistances(self)

    def _get(self, name: str) -> Obstacle:
        if name not in self._obstacles:
            raise UnknownObstacle(name, self._obstacles)
        return self._obstacles[name]

    def move(self, name: str, position=None, rpy=None, velocity=None) -> Obstacle:
        """Move an obstacle (and/or change its velocity) without rebuilding the diagram."""
        old = self._get(name)
        X_WO = old.X_WO.copy()
        if position is not None:
            X_WO[:3, 3] = vector3(position, "position [m]")
        if rpy is not None:
            X_WO[:3, :3] = rotation_rpy(rpy)
        vel = old.velocity_W if velocity is None else vector3(velocity, "velocity [m/s]")
        # SceneGraph.ChangeShape(context, ..., X_FG) keeps the old pose for queries (Drake 1.51),
        # so the anchored geometry is re-registered at the new pose instead.
        self._unregister(self._ids[name])
        self._ids[name] = self._register(name, old.shape, X_WO)
        new = Obstacle(name, old.shape, X_WO, vel)
        self._obstacles[name] = new
        self._obstacles_changed()
        return new

    def remove(self, name: str) -> None:
        """Remove an obstacle."""
        self._get(name)
        self._unregister(self._ids[name])
        del self._obstacles[name]
        del self._ids[name]
        self._obstacles_changed()

    def step(self, dt: float) -> None:
        """Advance every moving obstacle by ``velocity · dt`` [s]."""
        if isinstance(dt, (bool, str, bytes)) or not isinstance(dt, (int, float, np.number)) or not np.isfinite(dt):
            raise SceneError(f"dt must be a finite number of seconds, got {dt!r}")
        for name, obstacle in list(self._obstacles.items()):
            if np.any(obstacle.velocity_W != 0):
                self.move(name, position=obstacle.position + obstacle.velocity_W * float(dt))

    # --- exact distances (drake_mh.scene.exact) --------------------------------------------------------

    def distances(self, q, max_distance: float = np.inf) -> list[DistancePair]:
        """Exact signed distances of every link-obstacle (and self) pair within ``max_distance``.

        One row per pair of collision geometries (a link with several geometries has several
        rows); how each is computed: :mod:`drake_mh.scene.exact`.

        Returns:
            Pairs sorted by distance (closest first), robot side first.

        Raises:
            SceneError: the robot has no collision geometry, or a bad ``max_distance``.
            InvalidConfiguration: ``q`` is not ``(nq,)`` finite numbers.
        """
        self._require_geometry()
        if not (isinstance(max_distance, (int, float, np.number)) and not isinstance(max_distance, bool)
                and max_distance >= 0):  # NaN fails this too
            raise SceneError(f"max_distance must be a number >= 0 [m] (inf for all pairs), got {max_distance!r}")
        return self._exact.distances(q, float(max_distance))

    def _require_geometry(self) -> None:
        if not self._robot_ids:
            raise SceneError(
                f"robot {self.robot.name!r} has no collision geometry, so its distance to obstacles "
                "is unknown (not infinite); add <collision> elements to its links in the model file")

    def min_distance(self, q) -> float:
        """Smallest exact signed distance [m] over all pairs (link-obstacle, and link-link with
        ``self_collision``).

        Exact as :meth:`distances` (:mod:`drake_mh.scene.exact`), without building the pairs:
        they are refined in the order of a cheap lower bound until it reaches the minimum.

        Returns:
            The distance; ``inf`` when there is nothing to collide with (no obstacle, and no
            self-collision pair).

        Raises:
            SceneError: the robot has no collision geometry.
        """
        self._require_geometry()
        return self._exact.min_distance(q)

    def in_collision(self, q, margin: float = 0.0) -> bool:
        """Whether some pair is closer than ``margin`` [m] (exact, Drake)."""
        if isinstance(margin, bool) or not isinstance(margin, (int, float, np.number)) or not np.isfinite(margin):
            raise SceneError(f"margin must be a finite number [m], got {margin!r}")  # NaN read 'no collision'
        return self.min_distance(q) < margin

    def exact_min_distance(self, Q) -> np.ndarray:
        """:meth:`min_distance` for each row of ``Q (N, nq)`` (one compiled call per row; for checks)."""
        self._require_geometry()
        Q = self.robot.check_Q(Q)
        exact = self._exact
        return np.array([exact.min_distance(q) for q in Q], dtype=float).reshape(-1)

    # --- batched conservative distances (sphere model) ----------------------------------------

    @functools.cached_property
    def sphere_model(self) -> SphereModel:
        """The robot's :class:`SphereModel` (the robot's own unless another tolerance was asked).

        Raises:
            SceneError: the robot has no collision geometry.
        """
        self._require_geometry()
        if self._sphere_tolerance == DEFAULT_TOLERANCE:
            return self.robot.sphere_model
        return SphereModel.from_robot(self.robot, self._sphere_tolerance)

    @functools.cached_property
    def _compiled_spheres(self):
        model = self.sphere_model
        return self.robot.batch.compile_points(list(model.links), model.centres_B)

    @functools.cached_property
    def _compiled_cores(self):
        return self.robot.batch.compile_points(*_module("penetration").core_points(self.sphere_model))

    @functools.cached_property
    def _core_arrays(self) -> tuple:
        """The sphere model's geometries as the penetration correction reads them."""
        return _module("penetration").core_arrays(self.sphere_model)

    def _correct_penetrations(self, Q, values) -> None:
        """``values (n, K)`` in place, for ``Q (n, nq)``: the negative ones corrected where the
        sphere model's value can be too shallow (:func:`drake_mh.scene.penetration.correct_clearances`)."""
        _module("penetration").correct_clearances(values, self.robot.batch.points(np.ascontiguousarray(Q),
                                                                           *self._compiled_cores),
                                          *self._core_arrays, *self.obstacle_arrays[:3], self.obstacle_arrays[4],
                                          *self._obstacle_polytopes)

    @property
    def _obstacle_polytopes(self) -> tuple:
        """The obstacles' polytopes as the penetration correction reads them (rebuilt after
        add/move/remove)."""
        if self._polytopes is None:
            self._polytopes = _module("penetration").obstacle_polytopes(self._obstacles.values())
        return self._polytopes

    def sphere_centres(self, Q) -> np.ndarray:
        """World positions ``(N, S, 3)`` of the sphere model's centres."""
        return self.robot.batch.points(Q, *self._compiled_spheres)

    def _kernel_batch(self, Q) -> bool:
        """Whether ``Q`` is a C-contiguous float64 ``(N, nq)`` batch that the compiled entry points
        read as it is (they check its finiteness while transposing it)."""
        return (type(Q) is _NDARRAY and Q.dtype is _F8 and Q.ndim == 2 and Q.shape[1] == self._nq
                and Q.flags.c_contiguous)

    def _sphere_clearances(self, Q, overall: bool) -> tuple:
        """``(Q (N, nq) checked, values)``: the sphere model's clearance per obstacle ``(N, K)``,
        or the smallest over them ``(N, 1)`` with ``overall``, before any penetration correction
        (:meth:`drake_mh.scene.batch.CollisionModel.obstacle_clearance_function`, bound to the
        current obstacles)."""
        arrays = self.obstacle_arrays
        if self._clearance_function is None:
            self._clearance_function = self.collision_model.obstacle_clearance_function(arrays)
        if self._kernel_batch(Q):
            out = self._clearance_function(Q, overall)  # the kernel checks finiteness as it transposes
            if out is not None:
                return Q, out
        Q = self.robot.check_Q(Q)  # raises on bad input
        return Q, self._clearance_function(Q, overall)

    def batch_obstacle_distances(self, Q) -> np.ndarray:
        """Conservative clearance ``(N, K)`` of the robot to each of the K obstacles [m].

        Never more than the exact distance (penetration included); at most
        ``sphere_model.bound`` less where the exact distance is >= 0 (module docstring).
        Compiled (:mod:`drake_mh.scene.kernels.collision`): each link's bounding sphere first,
        its spheres only where they can hold the minimum.

        Raises:
            SceneError: the robot has no collision geometry.
        """
        Q, out = self._sphere_clearances(Q, overall=False)
        deep_rows = np.flatnonzero((out < 0).any(axis=1)) if out.size else np.zeros(0, int)
        if len(deep_rows):  # a sphere penetrates: the union's value may be too shallow there
            deep = out[deep_rows]
            self._correct_penetrations(Q[deep_rows], deep)
            out[deep_rows] = deep
        owners = self.obstacle_owners
        if len(owners) != len(self._obstacles):  # a mesh's pieces: the smallest value per mesh
            out = np.minimum.reduceat(out, np.flatnonzero(np.r_[True, owners[1:] != owners[:-1]]), axis=1)
        return out

    # --- batched boolean queries and certified segments (sphere model, compiled) ---------------

    @functools.cached_property
    def collision_model(self):
        """The sphere model grouped per link for the compiled kernels
        (:class:`drake_mh.scene.batch.CollisionModel`), with this scene's self-collision pairs."""
        from drake_mh.scene.batch import CollisionModel

        return CollisionModel(self.robot, self.sphere_model, self._self_link_pairs)

    def _obstacles_changed(self) -> None:
        """Drop what was bound to the obstacles (rebuilt on the next query)."""
        self._obstacle_arrays = self._free_function = self._free_one = self._clearance_function = None
        self._polytopes = self._owners = None
        self._planner_bindings = {}

    @property
    def obstacle_arrays(self) -> tuple:
        """The obstacles as the compiled kernels read them (rebuilt after add/move/remove)."""
        if self._obstacle_arrays is None:
            from drake_mh.scene.batch import obstacle_arrays  # here: an import costs about 0.7 µs a call

            self._obstacle_arrays = obstacle_arrays(self._obstacles.values())
            self._free_function = self._free_one = self._clearance_function = None
        return self._obstacle_arrays

    def planner_binding(self, key, build):
        """``build(self)``, computed once per ``key`` and kept until the obstacles change (:meth:`add`,
        :meth:`move`, :meth:`remove`): what a compiled planner derives from :attr:`obstacle_arrays`
        and :attr:`collision_model` (its kernel's arguments) is built once, not at every plan.

        Args:
            key: names the planner's binding (hashable, e.g. the planner's function).
            build: ``build(scene) -> value``; it reads the scene, never changes it.
        """
        value = self._planner_bindings.get(key)
        if value is None:
            value = self._planner_bindings[key] = build(self)
        return value

    @property
    def obstacle_owners(self) -> np.ndarray:
        """``(K,)`` for each obstacle of :attr:`obstacle_arrays` (a mesh has one per convex
        piece) the index of its obstacle in :attr:`obstacles`' order."""
        if self._owners is None:
            from drake_mh.scene.batch import obstacle_owners

            self._owners = obstacle_owners(self._obstacles.values())
        return self._owners

    def _free(self):
        """The compiled boolean query bound to the current obstacles (rebuilt when they change)."""
        arrays = self.obstacle_arrays
        if self._free_function is None:  # the compiled core's where it is built
            self._free_function = compiled_check.free_function(self.collision_model, arrays)
        return self._free_function

    def collision_free(self, Q, clearance: float = 0.0, self_clearance: float = 0.0):
        """Whether each configuration is certified free: every sphere of the model at least
        ``clearance`` [m] from every obstacle and, with ``self_collision``, every checked link
        pair at least ``self_clearance`` apart.

        Conservative: ``True`` implies the exact geometry is at least as clear; a configuration
        up to ``sphere_model.bound`` clearer than asked may read ``False``. Compiled (the C++
        core where built: docs/native.md), SIMD across configurations, a block ends once all its
        configurations collide. One float64 ``(nq,)`` configuration with float clearances takes a
        scalar entry point (same answer, first collision ends it): about 1 µs (docs/collision.md).

        Args:
            Q: ``(N, nq)`` configurations, or one ``(nq,)``.
            clearance, self_clearance: required clearances [m], >= 0.

        Returns:
            ``(N,)`` bool, or one bool for one ``(nq,)`` configuration.

        Raises:
            SceneError: the robot has no collision geometry, or a bad clearance.
        """
        one = self._free_one  # (entry, buffer) bound to the current obstacles (None after a change)
        if (one is not None and type(Q) is _NDARRAY and Q.dtype is _F8 and Q.ndim == 1 and len(Q) == self._nq
                and type(clearance) is float and type(self_clearance) is float):
            entry, buffer = one
            free = entry(Q, clearance, self_clearance, buffer)  # one configuration: ~0.9 µs in all
            if free >= 0:
                return free > 0  # else a NaN in Q or a bad clearance: the checks below raise
        if not self._robot_ids:
            self._require_geometry()
        if type(clearance) is not float or type(self_clearance) is not float \
                or not (0.0 <= clearance < _INF and 0.0 <= self_clearance < _INF):
            check_clearance = _module("segments").check_clearance
            clearance = check_clearance(clearance, "clearance")
            self_clearance = check_clearance(self_clearance, "self_clearance")
        free = self._free()
        if self._kernel_batch(Q):
            out = free(Q, clearance, self_clearance)  # the kernel checks finiteness as it transposes
            if out is not None:
                return out
        elif type(Q) is _NDARRAY and Q.dtype is _F8 and Q.shape == self._q_shape and Q.flags.c_contiguous:
            if self._free_one is None:  # the next one-configuration calls take the path above
                self._free_one = free.make_one()
            out = free(Q.reshape(1, -1), clearance, self_clearance)  # one configuration: no copy
            if out is not None:
                return bool(out[0])
            self.robot.check_q(Q)  # raises, naming the joints
        one = np.ndim(Q) == 1
        out = free(self.robot.check_Q(Q), clearance, self_clearance)  # raises on bad input
        return bool(out[0]) if one else out

    def segment_free(self, q_a, q_b, clearance: float = 0.0, self_clearance: float = 0.0) -> bool:
        """Whether the straight joint-space motion ``q_a -> q_b`` is certified free *for every
        configuration on it* (:func:`drake_mh.scene.segments.certify_segments`).

        Raises:
            SceneError: ``q_a`` or ``q_b`` is not one configuration ``(nq,)`` (several segments:
                :meth:`certify_segments`), or a bad clearance.
        """
        for name, q in (("q_a", q_a), ("q_b", q_b)):
            try:
                several = np.ndim(q) > 1
            except ValueError:  # ragged: certify_segments names what is wrong
                several = False
            if several:
                raise SceneError(f"segment_free checks one segment: {name} must be one configuration "
                                 f"({self._nq},), got shape {np.shape(q)}; certify several segments with "
                                 "certify_segments(QA, QB)")
        return bool(_module("segments").certify_segments(self, q_a, q_b, clearance, self_clearance).certified[0])

    def certify_segments(self, QA, QB, clearance: float = 0.0, self_clearance: float = 0.0, **options):
        """Certify many straight segments ``QA[i] -> QB[i]``: see
        :func:`drake_mh.scene.segments.certify_segments`."""
        return _module("segments").certify_segments(self, QA, QB, clearance, self_clearance, **options)

    def certify_path(self, Q, clearance: float = 0.0, self_clearance: float = 0.0, **options):
        """Certify the piecewise-linear joint-space motion through the rows of ``Q (M, nq)``:
        see :func:`drake_mh.scene.segments.certify_path`."""
        return _module("segments").certify_path(self, Q, clearance, self_clearance, **options)

    def batch_min_distance(self, Q) -> np.ndarray:
        """Conservative minimum clearance ``(N,)`` to the obstacles [m] (``inf`` if there is none).

        Never more than the exact distance of :meth:`min_distance` (in penetration too), at most
        ``sphere_model.bound`` less where that is >= 0 (module docstring). Robot self-distances
        are not included (use :meth:`distances` with ``self_collision``).

        Raises:
            SceneError: the robot has no collision geometry.
        """
        self._require_geometry()
        if not self._obstacles:
            Q = self.robot.check_Q(Q)
            return np.full(Q.shape[0], np.inf)
        Q, out = self._sphere_clearances(Q, overall=True)
        out = out[:, 0]
        deep = np.flatnonzero(out < 0)  # a sphere penetrates: per obstacle, corrected
        if len(deep):
            values = np.full((len(deep), len(self.obstacle_owners)), -1.0)  # all obstacles: the negative ones count
            self._correct_penetrations(Q[deep], values)
            out[deep] = values.min(axis=1)
        return out

    # --- scene files (drake_mh.scene.files, docs/scene_files.md) --------------------------------

    @classmethod
    def from_file(cls, path, robot, format: str | None = None, packages=None, movable: str = "error",
                  **options) -> Scene:
        """A new scene of ``robot`` (``**options``: :class:`Scene`'s) with the obstacles of a scene
        file: any of :data:`drake_mh.scene.files.SCENE_FORMATS`; the file is read first. Arguments
        and errors: :meth:`load`."""
        from drake_mh.scene.files import read_scene

        scene_file = read_scene(path, format, packages, movable)
        scene = cls(robot, **options)
        scene.load(scene_file)
        return scene

    def load(self, path, format: str | None = None, packages=None, movable: str = "error") -> list[str]:
        """Add the obstacles of a scene file (or of a :class:`drake_mh.scene.files.SceneFile`),
        all or nothing; ``format``, ``packages``, ``movable``: as
        :func:`drake_mh.scene.files.read_scene` takes them. Returns the names added.

        Raises:
            SceneFileNotFound: no such file.
            SceneFileError: a malformed or unsupported file (naming the file, the entry and what
                is expected), a name the scene has, or an obstacle it refuses: nothing is added.
        """
        from drake_mh.scene.files import SceneFile, add_to_scene, read_scene

        scene_file = path if isinstance(path, SceneFile) else read_scene(path, format, packages, movable)
        return add_to_scene(self, scene_file)

    def save(self, path, name: str = "") -> list:
        """Write the obstacles as drake_mh scene YAML (``.yaml`` / ``.yml``), which :meth:`load`
        reads back the same to float precision; returns the files written (point clouds go
        beside it as ``.npy``). Raises SceneFileError for another suffix or a missing folder."""
        from drake_mh.scene.files import write_scene

        return write_scene(path, self._obstacles.values(), name)

    def __repr__(self) -> str:
        return f"Scene({self.robot.name!r}, obstacles={list(self._obstacles)})"

