"""Independent references for the tests: Drake's own queries on a fresh plant, Pinocchio and coal
for shipped meshes, dense sampling of joint-space motions, finite differences of positions.

Nothing here calls drake_mh's kinematics, distances, certificates or dynamics: a robot's model
file is parsed again into a new ``MultibodyPlant`` + ``SceneGraph``, a scene's obstacles are
registered there as anchored collision geometry (built from their dimensions, not from
``Shape.to_drake()``), and every answer is a Drake query on that plant. What the tests take
from drake_mh is only the *specification* of what to check: the robot's model text, its joint
names, its locked joints, and which link pairs a scene leaves out of self-collision.

Known limits of Drake as a reference (REFERENCES.md, drake_mh.scene.exact): its GJK is
optimistic by up to a few millimetres for capsule-box and capsule-cylinder pairs (never for
sphere obstacles, which it computes in closed form), and its capsule-capsule query can hang on
collinear touching axes. So a test compares with Drake one-sidedly where boxes or cylinders are
involved ("claimed free => Drake finds it free"), and uses no capsule obstacles with Drake.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _drake_shape(shape):
    """The pydrake shape of a drake_mh primitive, from its dimensions."""
    from pydrake.geometry import Box, Capsule, Cylinder, Sphere

    kind = type(shape).__name__
    if kind == "Sphere":
        return Sphere(float(shape.radius))
    if kind == "Box":
        return Box(*map(float, shape.size))
    if kind == "Cylinder":
        return Cylinder(float(shape.radius), float(shape.length))
    if kind == "Capsule":
        return Capsule(float(shape.radius), float(shape.length))
    raise TypeError(f"no Drake reference for obstacle shape {kind}")


class FreshDrake:
    """A robot's model parsed into a new plant, with obstacles anchored in the world.

    Args:
        robot: the drake_mh Robot whose model file (``robot.source`` when it is a file, else the
            text it was built from) is parsed again.
        obstacles: ``[(shape, X_WO (4, 4))]`` or a drake_mh Scene (its obstacles, as they are now).
        self_collision: also report robot-robot pairs (Drake's default filter of adjacent links,
            plus ``ignore_link_pairs``); otherwise robot-robot pairs are filtered out.
        ignore_link_pairs: ``[(link_a, link_b)]`` left out of self-collision.
    """

    def __init__(self, robot, obstacles=(), self_collision: bool = False, ignore_link_pairs=()):
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet, Role
        from pydrake.math import RigidTransform, RotationMatrix
        from pydrake.multibody.parsing import Parser
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
        from pydrake.systems.framework import DiagramBuilder

        if hasattr(obstacles, "obstacles"):  # a Scene
            obstacles = [(o.shape, o.X_WO) for o in obstacles.obstacles.values()]
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
        parser = Parser(plant)
        source = Path(str(robot.source))
        if robot.source != "<string>" and source.is_file():
            parser.AddModels(str(source))
        else:
            parser.AddModelsFromString(robot.urdf, "urdf")
        inspector = scene_graph.model_inspector()
        for i, (shape, X_WO) in enumerate(obstacles):
            X_WO = np.asarray(X_WO, dtype=float)
            plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(RotationMatrix(X_WO[:3, :3]),
                                                                               X_WO[:3, 3]),
                                            _drake_shape(shape), f"reference_obstacle_{i}", CoulombFriction(0.5, 0.5))
        plant.Finalize()
        robot_ids = [g for g in inspector.GetAllGeometryIds(Role.kProximity)
                     if inspector.GetFrameId(g) != inspector.world_frame_id()]
        manager = scene_graph.collision_filter_manager()
        if not self_collision:
            manager.Apply(CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_ids)))
        else:
            for a, b in ignore_link_pairs:
                ga, gb = (inspector.GetGeometries(plant.GetBodyFrameIdOrThrow(plant.GetBodyByName(n).index()),
                                                  Role.kProximity) for n in (a, b))
                manager.Apply(CollisionFilterDeclaration().ExcludeBetween(GeometrySet(ga), GeometrySet(gb)))
        self.plant, self.scene_graph = plant, scene_graph
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        self.sg_context = scene_graph.GetMyContextFromRoot(self.context)
        self._port = scene_graph.get_query_output_port()
        # drake_mh's q (its joint order, locked joints left out) -> this plant's positions
        self._q_full = plant.GetPositions(self.plant_context).copy()
        for name, value in getattr(robot, "locked_joints", {}).items():
            self._q_full[plant.GetJointByName(name).position_start()] = value
        self._index = np.array([plant.GetJointByName(name).position_start() for name in robot.joint_names])

    def set(self, q) -> None:
        q_full = self._q_full.copy()
        q_full[self._index] = q
        self.plant.SetPositions(self.plant_context, q_full)

    def pairs(self, q, max_distance: float = np.inf) -> list:
        """Drake's ``ComputeSignedDistancePairwiseClosestPoints`` at ``q``."""
        self.set(q)
        return self._port.Eval(self.sg_context).ComputeSignedDistancePairwiseClosestPoints(max_distance)

    def min_distance(self, q, max_distance: float = np.inf) -> float:
        """Smallest signed distance [m] over the unfiltered pairs (``inf`` if none is within
        ``max_distance``)."""
        return min((p.distance for p in self.pairs(q, max_distance)), default=np.inf)

    def min_distances(self, Q, max_distance: float = np.inf) -> np.ndarray:
        """:meth:`min_distance` for each row of ``Q (N, nq)``."""
        return np.array([self.min_distance(q, max_distance) for q in np.atleast_2d(Q)])

    def capsules(self, q) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """``[(link, axis end a (3,), axis end b (3,), radius)]`` of every capsule and sphere
        (an axis of length 0) of the robot at ``q``: poses from this plant's query, sizes from
        its shapes."""
        from pydrake.geometry import Role

        self.set(q)
        query = self._port.Eval(self.sg_context)
        inspector = query.inspector()
        out = []
        for gid in inspector.GetAllGeometryIds(Role.kProximity):
            if inspector.GetFrameId(gid) == inspector.world_frame_id():
                continue
            shape, X = inspector.GetShape(gid), query.GetPoseInWorld(gid).GetAsMatrix4()
            kind = type(shape).__name__
            if kind not in ("Capsule", "Sphere"):
                raise TypeError(f"no closed form for a {kind} link")
            half = 0.5 * shape.length() * X[:3, 2] if kind == "Capsule" else np.zeros(3)
            link = self.plant.GetBodyFromFrameId(inspector.GetFrameId(gid)).name()
            out.append((link, X[:3, 3] - half, X[:3, 3] + half, shape.radius()))
        return out

    def ball_distance(self, q, centre, radius: float) -> float:
        """Distance [m] of a ball to a robot of capsules and spheres, in closed form
        (:func:`ball_to_capsule` of each)."""
        return min(ball_to_capsule(centre, radius, capsule) for capsule in self.capsules(q))

    def _frame(self, frame: str):
        return self.plant.GetFrameByName(frame)

    def fk(self, q, frame: str) -> np.ndarray:
        """``X_WF (4, 4)`` of the frame named ``frame``."""
        self.set(q)
        return self._frame(frame).CalcPoseInWorld(self.plant_context).GetAsMatrix4()

    def jacobian(self, q, frame: str) -> np.ndarray:
        """Geometric Jacobian ``(6, nq)`` of the frame's origin, rows ``[ω; v]``, columns in
        drake_mh's joint order."""
        from pydrake.multibody.tree import JacobianWrtVariable

        self.set(q)
        J = self.plant.CalcJacobianSpatialVelocity(self.plant_context, JacobianWrtVariable.kQDot, self._frame(frame),
                                                   np.zeros(3), self.plant.world_frame(), self.plant.world_frame())
        return J[:, self._index]

    def inverse_dynamics(self, q, v, a) -> np.ndarray:
        """Joint torques ``M(q) a + C(q, v) v - τ_g(q)`` [N·m] (gravity included), from Drake's
        mass matrix, bias term and gravity forces (every joint of the model must be in ``q``)."""
        if len(self._index) != self.plant.num_positions():
            raise ValueError("inverse dynamics of a model with locked joints is not a reference here")
        self.set(q)
        v_full = np.zeros(self.plant.num_velocities())
        v_full[self._index] = v
        self.plant.SetVelocities(self.plant_context, v_full)
        M = self.plant.CalcMassMatrix(self.plant_context)[np.ix_(self._index, self._index)]
        bias = self.plant.CalcBiasTerm(self.plant_context)[self._index]
        gravity = self.plant.CalcGravityGeneralizedForces(self.plant_context)[self._index]
        return M @ a + bias - gravity


def ball_to_capsule(centre, radius: float, capsule) -> float:
    """Signed distance [m] of a ball to a capsule ``(name, axis end a, axis end b, radius)``:
    the point-to-segment distance from its centre to the axis, minus both radii."""
    _, a, b, r = capsule
    centre, u = np.asarray(centre, dtype=float), b - a
    t = 0.0 if not u.any() else float(np.clip((centre - a) @ u / (u @ u), 0.0, 1.0))
    return float(np.linalg.norm(centre - (a + t * u))) - r - radius


def dense_path(path, max_step: float = 0.005) -> np.ndarray:
    """The piecewise-linear joint-space motion through the rows of ``path (M, nq)``, sampled so
    that no joint moves more than ``max_step`` [rad] between two samples (ends included)."""
    path = np.atleast_2d(np.asarray(path, dtype=float))
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / max_step)))
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.vstack(out)


def finite_differences(position, t, h: float, order: int) -> np.ndarray:
    """Central difference of ``order`` (1, 2 or 3) of ``position(times) -> (N, nq)`` at ``t (N,)``.

    Each is a weighted *average* of that derivative over (at most) ``[t - 1.5 h, t + 1.5 h]`` with
    non-negative weights summing to one (a B-spline kernel), so its magnitude never exceeds the
    derivative's largest magnitude there, even across a jump: a bound check on it is exact up to
    round-off (about ``1e-16 / h**order``), and it is only as close to the peak as ``h`` allows.
    """
    t = np.asarray(t, dtype=float)
    if order == 1:
        return (position(t + 0.5 * h) - position(t - 0.5 * h)) / h
    if order == 2:
        return (position(t + h) - 2.0 * position(t) + position(t - h)) / h ** 2
    if order == 3:
        return (position(t + 1.5 * h) - 3.0 * position(t + 0.5 * h) + 3.0 * position(t - 0.5 * h)
                - position(t - 1.5 * h)) / h ** 3
    raise ValueError(order)


class PinocchioCoal:
    """A robot's model file read by Pinocchio (its own URDF parser and mesh loader), collision
    meshes turned into convex hulls by coal (qhull), placed by Pinocchio's FK; distances to
    obstacles by coal's GJK. The reference for robots whose meshes Drake cannot read (STL).

    Args:
        robot: the drake_mh Robot (its ``source`` file, joint order and locked joints).
        package_dirs: folders holding the packages of ``package://`` URIs.
    """

    def __init__(self, robot, package_dirs=()):
        import coal
        import pinocchio as pin

        self._pin, self._coal = pin, coal
        self.model, self.collision, _ = pin.buildModelsFromUrdf(str(robot.source),
                                                                package_dirs=[str(d) for d in package_dirs])
        self.data, self.collision_data = self.model.createData(), self.collision.createData()
        self.geometries = []
        for obj in self.collision.geometryObjects:
            geometry = obj.geometry
            if isinstance(geometry, coal.BVHModelBase):
                geometry.buildConvexHull(True, "Qt")
                geometry = geometry.convex
            self.geometries.append(geometry)
        self._q0 = pin.neutral(self.model)
        for name, value in robot.locked_joints.items():
            self._q0[self.model.idx_qs[self.model.getJointId(name)]] = value
        self._index = [self.model.idx_qs[self.model.getJointId(name)] for name in robot.joint_names]

    def _place(self, q) -> None:
        q_full = self._q0.copy()
        q_full[self._index] = q
        self._pin.framesForwardKinematics(self.model, self.data, q_full)
        self._pin.updateGeometryPlacements(self.model, self.data, self.collision, self.collision_data, q_full)

    def fk(self, q, frame: str) -> np.ndarray:
        """``X_WF (4, 4)`` of the frame named ``frame``."""
        self._place(q)
        return self.data.oMf[self.model.getFrameId(frame)].homogeneous

    def ball_distance(self, q, centre, radius: float) -> float:
        """Smallest distance [m] of the robot's collision geometry to a ball."""
        coal = self._coal
        self._place(q)
        ball, X_WB = coal.Sphere(float(radius)), coal.Transform3s(np.eye(3), np.asarray(centre, dtype=float))
        best = np.inf
        for geometry, M in zip(self.geometries, self.collision_data.oMg):
            result = coal.DistanceResult()
            best = min(best, coal.distance(geometry, coal.Transform3s(M.rotation, M.translation), ball, X_WB,
                                           coal.DistanceRequest(), result))
        return float(best)


class FreshPlant:
    """A new Drake plant (and scene graph) parsed from ``robot.model_text`` (what Drake read,
    meshes resolved: robots loaded with ``packages=`` too), joints ordered as the robot's; for
    torques, mass matrices, gravity and distances to primitive obstacles.

    Args:
        robot: the drake_mh robot (only its model text, format and joint names are read).
        obstacles: ``[(kind, size, position)]`` world-fixed obstacles for :meth:`min_distance`:
            ``("box", (lx, ly, lz), p)``, ``("sphere", r, p)``, ``("cylinder", (r, length), p)``.
    """

    def __init__(self, robot, obstacles=()):
        from pydrake.geometry import Box, Cylinder, Sphere
        from pydrake.math import RigidTransform
        from pydrake.multibody.parsing import Parser
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, CoulombFriction
        from pydrake.multibody.tree import BodyIndex, JointIndex
        from pydrake.systems.framework import DiagramBuilder

        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
        Parser(plant).AddModels(file_contents=robot.model_text,
                                file_type={"mjcf": "xml"}.get(robot.model_format, robot.model_format))
        children = {plant.get_joint(JointIndex(i)).child_body().index() for i in range(plant.num_joints())}
        for i in range(1, plant.num_bodies()):
            body = plant.get_body(BodyIndex(i))
            if body.index() not in children:
                plant.WeldFrames(plant.world_frame(), body.body_frame())
        self.obstacle_ids = set()
        shapes = {"box": lambda s: Box(*s), "sphere": lambda s: Sphere(s), "cylinder": lambda s: Cylinder(*s)}
        for k, (kind, size, position) in enumerate(obstacles):
            gid = plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(np.asarray(position, float)),
                                                  shapes[kind](size), f"obstacle{k}", CoulombFriction(0.5, 0.5))
            self.obstacle_ids.add(gid)
        plant.Finalize()
        self.plant, self.scene_graph = plant, scene_graph
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        joints = [plant.GetJointByName(n) for n in robot.joint_names]
        self.index = np.array([j.position_start() for j in joints])
        self.damping = np.array([float(np.sum(j.default_damping_vector())) for j in joints])

    def _set(self, q, v=None) -> None:
        x = np.zeros(self.plant.num_positions())
        x[self.index] = q
        self.plant.SetPositions(self.plant_context, x)
        if v is not None:
            xv = np.zeros(self.plant.num_velocities())
            xv[self.index] = v
            self.plant.SetVelocities(self.plant_context, xv)

    def torques(self, Q, V, A) -> np.ndarray:
        """``(N, nq)`` joint torques ``M a + C v - τ_g(q) + damping·v`` [N·m]: Drake's
        ``CalcInverseDynamics`` with no applied forces, minus ``CalcGravityGeneralizedForces``,
        plus the joints' viscous damping (a force element Drake leaves out of inverse dynamics)."""
        from pydrake.multibody.tree import MultibodyForces

        out = []
        for q, v, a in zip(np.atleast_2d(Q), np.atleast_2d(V), np.atleast_2d(A)):
            self._set(q, v)
            acc = np.zeros(self.plant.num_velocities())
            acc[self.index] = a
            tau = self.plant.CalcInverseDynamics(self.plant_context, acc, MultibodyForces(self.plant))
            tau = tau - self.plant.CalcGravityGeneralizedForces(self.plant_context)
            out.append(tau[self.index] + self.damping * v)
        return np.array(out)

    def mass_matrix(self, q) -> np.ndarray:
        """``M(q) (nq, nq)`` from ``CalcMassMatrix``."""
        self._set(q)
        M = self.plant.CalcMassMatrix(self.plant_context)
        return M[np.ix_(self.index, self.index)]

    def gravity(self, q) -> np.ndarray:
        """``(nq,)`` torques holding the arm still: ``-CalcGravityGeneralizedForces``."""
        self._set(q)
        return -self.plant.CalcGravityGeneralizedForces(self.plant_context)[self.index]

    def min_distance(self, q) -> float:
        """Smallest signed distance [m] between the robot and the obstacles at ``q``."""
        self._set(q)
        query = self.scene_graph.get_query_output_port().Eval(self.scene_graph.GetMyContextFromRoot(self.context))
        best = np.inf
        for pair in query.ComputeSignedDistancePairwiseClosestPoints(1.0):
            if (pair.id_A in self.obstacle_ids) != (pair.id_B in self.obstacle_ids):
                best = min(best, pair.distance)
        return float(best)
