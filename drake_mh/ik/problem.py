"""The inverse-kinematics problem: target, tolerances, constraints and a vectorized objective.

:class:`IKProblem` states *what* is asked of every IK method (metaheuristics, the hybrid,
Jacobian and Drake baselines), so that all of them are solved and verified on the same thing:

* a target position ``p_WT (3,)`` (position-only IK as in §3.2 / Algorithm 1 of the framework
  paper) or a full pose ``X_WT (4, 4)`` (position + orientation);
* tolerances on the position error ``||p_WT - p_WE(q)||`` [m] and on the orientation error,
  the rotation angle of ``R_WT R_WE(q)ᵀ`` [rad];
* joint limits (the search box);
* optionally obstacles from a :class:`drake_mh.scene.Scene` with a clearance margin [m], a
  reference configuration ``q_ref`` with a joint-displacement penalty (continuity along a path)
  and a manipulability reward.

:meth:`IKProblem.objective` evaluates whole populations ``Q (P, nq) -> (P,)`` through the
batched kernel (``Robot.batch``) and the scene's sphere model; no Python loop over individuals.
Success is never read from this objective: :func:`drake_mh.ik.result.verify` recomputes it
with Drake.
"""

from __future__ import annotations

import functools
import math
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from drake_mh.errors import InvalidIKProblem

__all__ = ["IKProblem", "ReachBound", "reach_bound", "rotation_angle"]

_SQRT8 = 2.0 * np.sqrt(2.0)


def rotation_angle(R_WE: np.ndarray, R_WT: np.ndarray) -> np.ndarray:
    """Angle [rad] of the rotation between ``R_WE (..., 3, 3)`` and ``R_WT (3, 3)``.

    Uses ``||R_WE - R_WT||_F = 2√2 sin(θ/2)``, accurate near θ = 0 (where ``arccos`` of the
    trace loses half the digits: 1e-8 rad would read as ~1.5e-8 or 0).
    """
    diff = np.linalg.norm((R_WE - R_WT).reshape(*R_WE.shape[:-2], 9), axis=-1)
    return 2.0 * np.arcsin(np.minimum(diff / _SQRT8, 1.0))


@dataclass(frozen=True)
class ReachBound:
    """A sphere that contains every reachable end-effector position.

    Attributes:
        p_WO: ``(3,)`` centre [m]: the origin of the first joint of the chain (fixed in W).
        radius: [m] sum of the link lengths from that joint to the end effector (joint-origin
            to joint-origin distances, which revolute joints keep constant) plus the stroke of
            prismatic joints.
        joint: name of the first joint.
    """

    p_WO: np.ndarray
    radius: float
    joint: str

    def distance(self, p_WT) -> float:
        """Distance [m] of a point from the centre."""
        return math.dist(np.asarray(p_WT, dtype=float).tolist(), self.p_WO.tolist())


_REACH_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: per scene: {obstacle state: reason or None} of :meth:`IKProblem.obstructed_reason`
_OBSTRUCTED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def reach_bound(robot, frame: str | None = None) -> ReachBound:
    """Computes a :class:`ReachBound` of ``frame`` (default the end effector) from the plant.

    Cached per robot object and frame (a few hundred µs of Drake queries otherwise, paid by
    every solve).

    Walks the kinematic chain from the frame's body to the world. For a revolute joint the
    child frame origin stays on the joint axis through the parent frame origin, so the distance
    from one joint origin to the next (fixed on one rigid body) does not depend on ``q``; the
    sum of these distances, plus the distance from the last joint to the frame and the largest
    displacement of each prismatic joint, bounds how far the frame can be from the first
    joint's origin (triangle inequality).

    Args:
        robot: a :class:`drake_mh.robot.Robot`.
        frame: frame name; default ``robot.ee_frame_name``.
    """
    cache = _REACH_CACHE.setdefault(robot, {})
    if frame not in cache:
        cache[frame] = _compute_reach_bound(robot, frame)
    return cache[frame]


def _compute_reach_bound(robot, frame: str | None) -> ReachBound:
    plant = robot.plant
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, robot.home)
    target_frame = robot._frame(frame)
    joint_of_child = {}
    from pydrake.multibody.tree import JointIndex

    for i in range(plant.num_joints()):
        joint = plant.get_joint(JointIndex(i))
        joint_of_child[int(joint.child_body().index())] = joint
    chain = []  # joints from the frame's body up to the world
    body = target_frame.body()
    world = int(plant.world_body().index())
    while int(body.index()) != world:
        joint = joint_of_child[int(body.index())]
        chain.append(joint)
        body = joint.parent_body()
    chain.reverse()
    moving = [j for j in chain if j.num_positions() > 0]
    p_W = [target_frame.CalcPoseInWorld(context).translation()]
    if not moving:
        return ReachBound(np.asarray(p_W[0]), 0.0, "")
    radius = 0.0
    previous_child = None
    for joint in moving:
        p_F = joint.frame_on_parent().CalcPoseInWorld(context).translation()
        p_M = joint.frame_on_child().CalcPoseInWorld(context).translation()
        if previous_child is not None:
            radius += float(np.linalg.norm(p_F - previous_child))
        if joint.type_name() == "prismatic":
            radius += float(np.max(np.abs([joint.position_lower_limits()[0], joint.position_upper_limits()[0]])))
        previous_child = p_M
    radius += float(np.linalg.norm(p_W[0] - previous_child))
    first = moving[0]
    p_WO = first.frame_on_parent().CalcPoseInWorld(context).translation()
    return ReachBound(np.asarray(p_WO, dtype=float), radius, first.name())


def _positive(name: str, value: Any, allow_zero: bool = False) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InvalidIKProblem(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        kind = "non-negative" if allow_zero else "positive"
        raise InvalidIKProblem(f"{name} must be a {kind} finite number, got {value}")
    return value


def _is_rotation(R: list) -> bool:
    """Whether the nested list ``R`` (3 x 3) is orthonormal to 1e-6 with a positive determinant.

    Scalar Python: numpy's ``R @ R.T``, ``det`` and reductions cost ~12 µs per target here,
    about a third of building an :class:`IKProblem` (paid by every solve).
    """
    for i in range(3):
        for j in range(i + 1):
            dot = R[i][0] * R[j][0] + R[i][1] * R[j][1] + R[i][2] * R[j][2]
            if abs(dot - (1.0 if i == j else 0.0)) > 1e-6:
                return False
    det = (R[0][0] * (R[1][1] * R[2][2] - R[1][2] * R[2][1]) - R[0][1] * (R[1][0] * R[2][2] - R[1][2] * R[2][0])
           + R[0][2] * (R[1][0] * R[2][1] - R[1][1] * R[2][0]))
    return det >= 0.0


def _rotation_from_rpy(rpy) -> np.ndarray:
    from pydrake.math import RollPitchYaw

    return RollPitchYaw(np.asarray(rpy, dtype=float)).ToRotationMatrix().matrix()


@dataclass(frozen=True, eq=False)
class IKProblem:
    """Inverse kinematics of one target for one robot (framework paper §3.2, Algorithm 1).

    Args:
        robot: a :class:`drake_mh.robot.Robot`.
        target: ``p_WT (3,)`` [m] (position only, unless ``rpy`` is given) or ``X_WT (4, 4)``.
        rpy: roll-pitch-yaw [rad] of the target orientation ``R_WT`` (Drake's convention,
            ``R = Rz(yaw) Ry(pitch) Rx(roll)``) when ``target`` is a position.
        position_tolerance: [m] on ``||p_WT - p_WE||``; default 1e-3 (1 mm, the
            position-only IK of the framework paper). The TRAC-IK protocol uses 1e-5.
        orientation_tolerance: [rad] on the rotation angle between ``R_WT`` and ``R_WE``;
            default 1e-2. The TRAC-IK protocol uses 1e-5 (per roll/pitch/yaw component there;
            a bound on the angle is at least as strict).
        orientation_weight: [m/rad] weight of the angle in the objective
            ``||Δp|| + w_o θ`` (and of the rotational rows in least-squares steps); default 1.
        scene: obstacles; ``None`` for none. Collision is judged by Drake's exact signed
            distance in verification and by the conservative sphere model in the objective.
        clearance: [m] required distance to the obstacles (0: touching is allowed).
        collision_weight: [1] penalty per metre of missing clearance in the objective
            (default 100: 1 cm of penetration costs as much as 1 m of position error).
        q_ref: reference configuration ``(nq,)`` (e.g. the previous point of a path).
        ref_weight: [m/rad] weight of ``||q - q_ref||`` in the objective; 0 disables it.
        manipulability_weight: [m] reward ``-w μ(q)`` with Yoshikawa's translational
            manipulability (ESM paper eq. (3)); 0 disables it.
        frame: end-effector frame; default ``robot.ee_frame_name``.

    Raises:
        InvalidIKProblem: bad target shape, non-orthonormal rotation, ``rpy`` given with a
            pose, non-positive tolerances, negative weights, a scene of another robot.
        InvalidConfiguration: ``q_ref`` of the wrong shape.
    """

    robot: Any
    target: Any
    rpy: Any = None
    position_tolerance: float = 1e-3
    orientation_tolerance: float = 1e-2
    orientation_weight: float = 1.0
    scene: Any = None
    clearance: float = 0.0
    collision_weight: float = 100.0
    q_ref: Any = None
    ref_weight: float = 0.0
    manipulability_weight: float = 0.0
    frame: str | None = None

    def __post_init__(self):
        set_ = functools.partial(object.__setattr__, self)
        from drake_mh.robot import Robot

        if not isinstance(self.robot, Robot):
            raise InvalidIKProblem(f"robot must be a drake_mh Robot (drake_mh.load_robot(...)), got "
                                   f"{type(self.robot).__name__}")
        try:  # numpy raises ValueError on ragged nested lists, in iscomplexobj too
            target = None if self.target is None or np.iscomplexobj(self.target) else np.asarray(self.target, float)
        except (TypeError, ValueError):
            raise InvalidIKProblem(f"target must be a position (3,) or a pose (4, 4), got {self.target!r}") from None
        if target is None:
            raise InvalidIKProblem(f"target must be a real position (3,) [m] or a pose (4, 4), got {self.target!r}")
        if not np.isfinite(target).all():
            raise InvalidIKProblem("target contains NaN or inf")
        if target.shape == (4, 4):
            if self.rpy is not None:
                raise InvalidIKProblem("give the orientation either in the (4, 4) target pose or as rpy, not both")
            p_WT, R_WT = target[:3, 3].copy(), target[:3, :3].copy()
            if not _is_rotation(R_WT.tolist()):
                raise InvalidIKProblem("the rotation block of the target pose is not a rotation matrix "
                                       "(orthonormal with determinant +1, to 1e-6)")
            a, b, c, d = target[3].tolist()
            if max(abs(a), abs(b), abs(c), abs(d - 1.0)) > 1e-12:
                raise InvalidIKProblem(f"the last row of a (4, 4) target pose must be [0, 0, 0, 1], got "
                                       f"{target[3].tolist()}")
        elif target.reshape(-1).shape == (3,):
            p_WT = target.reshape(-1).copy()
            R_WT = None
            if self.rpy is not None:
                try:
                    rpy = None if np.iscomplexobj(self.rpy) else np.asarray(self.rpy, dtype=float).reshape(-1)
                except (TypeError, ValueError):
                    rpy = None
                if rpy is None or rpy.shape != (3,) or not np.all(np.isfinite(rpy)):
                    raise InvalidIKProblem(f"rpy must be 3 finite angles [rad] (roll, pitch, yaw), got {self.rpy!r}")
                R_WT = _rotation_from_rpy(rpy)
        else:
            raise InvalidIKProblem(f"target must be a position (3,) or a pose (4, 4), got shape {target.shape}")
        set_("p_WT", p_WT)
        set_("R_WT", R_WT)
        for name in ("position_tolerance", "orientation_tolerance"):
            value = getattr(self, name)
            if not (type(value) is float and 0.0 < value < math.inf):  # the common case costs nothing
                set_(name, _positive(name, value))
        for name in ("orientation_weight", "clearance", "collision_weight", "ref_weight", "manipulability_weight"):
            value = getattr(self, name)
            if not (type(value) is float and 0.0 <= value < math.inf):
                set_(name, _positive(name, value, allow_zero=True))
        if self.scene is not None:
            from drake_mh.scene import Scene

            if not isinstance(self.scene, Scene):
                raise InvalidIKProblem(f"scene must be a drake_mh.scene.Scene (Scene(robot)) or None, got "
                                       f"{type(self.scene).__name__}")
            if self.scene.robot is not self.robot:
                raise InvalidIKProblem("the scene belongs to another Robot object; build it with Scene(robot) "
                                       "for the robot of this problem")
        if self.q_ref is not None:
            set_("q_ref", self.robot.check_q(self.q_ref, "q_ref").copy())  # not a view of the caller's array
        if self.frame is not None:
            self.robot._frame(self.frame)  # raises FrameNotFound listing the frames

    # --- derived quantities -----------------------------------------------------------------

    @property
    def nq(self) -> int:
        """Number of joints."""
        return self.robot.nq

    @property
    def full_pose(self) -> bool:
        """Whether the target has an orientation."""
        return self.R_WT is not None

    @property
    def lower(self) -> np.ndarray:
        """``(nq,)`` lower joint limits (continuous joints: -π)."""
        return self.robot.lower

    @property
    def upper(self) -> np.ndarray:
        """``(nq,)`` upper joint limits (continuous joints: +π)."""
        return self.robot.upper

    @property
    def has_obstacles(self) -> bool:
        """Whether the scene has obstacles (or checks self-collision)."""
        return self.scene is not None and (bool(self.scene.obstacles) or self.scene.self_collision)

    @property
    def X_WT(self) -> np.ndarray:
        """Target pose ``(4, 4)`` (identity rotation for a position-only target)."""
        X = np.eye(4)
        X[:3, 3] = self.p_WT
        if self.R_WT is not None:
            X[:3, :3] = self.R_WT
        return X

    @functools.cached_property
    def reach(self) -> ReachBound:
        """:class:`ReachBound` of the end-effector frame."""
        return reach_bound(self.robot, self.frame)

    def unreachable_reason(self) -> str | None:
        """A message if the target is provably out of reach, else ``None``.

        The target is out of reach when its distance from the first joint exceeds the reach
        bound by more than the position tolerance (see :func:`reach_bound`).
        """
        bound = self.reach
        distance = bound.distance(self.p_WT)
        if distance > bound.radius + self.position_tolerance:
            return (f"target out of reach: it is {distance:.4f} m from the first joint "
                    f"({bound.joint} at {np.round(bound.p_WO, 4).tolist()}) but the arm reaches at most "
                    f"{bound.radius:.4f} m from there (sum of link lengths); no solver was run")
        return None

    def obstructed_reason(self) -> str | None:
        """A message if an obstacle is closer than the clearance to a link no joint moves.

        Such a link (the base, anything welded to the world) is where it is in every
        configuration, so no solution exists; every method then fails at once instead of
        spending its budget (pinv/dls took 14 s). Checked with Drake's exact distance, cached
        per scene while its obstacles stay where they are.
        """
        scene = self.scene
        if scene is None or not scene.obstacles:
            return None
        key = (float(self.clearance),) + tuple(
            (name, o.X_WO.tobytes(), id(o.shape)) for name, o in scene.obstacles.items())
        cache = _OBSTRUCTED.setdefault(scene, {})
        if key not in cache:
            fixed = {name for name, (anchor, _) in self.robot.batch.chain.body_anchor.items() if anchor < 0}
            pairs = [p for p in scene.distances(self.robot.home, max_distance=self.clearance + 1e-9)
                     if not p.is_self and p.link in fixed and p.distance < self.clearance]
            cache.clear()
            cache[key] = None if not pairs else (
                f"obstacle {pairs[0].other!r} is {pairs[0].distance:.4f} m from link {pairs[0].link!r}, which no "
                f"joint moves (clearance {self.clearance:g} m): every configuration collides; no solver was run")
        return cache[key]

    # --- vectorized evaluation ---------------------------------------------------------------

    def pose_errors(self, Q) -> tuple[np.ndarray, np.ndarray]:
        """Position errors ``(P,)`` [m] and orientation errors ``(P,)`` [rad] of ``Q (P, nq)``.

        Orientation errors are zero for a position-only target.
        """
        X_WE = self.robot.batch.fk(Q, self.frame)
        e_p = np.linalg.norm(X_WE[:, :3, 3] - self.p_WT, axis=1)
        if self.R_WT is None:
            return e_p, np.zeros_like(e_p)
        return e_p, rotation_angle(X_WE[:, :3, :3], self.R_WT)

    def objective(self, Q) -> np.ndarray:
        """Fitness ``(P,)`` of a population ``Q (P, nq)`` (lower is better) [m].

        ``f = ||p_WT - p_WE|| + w_o θ + w_c max(0, clearance - d(q)) + w_ref ||q - q_ref||
        - w_m μ(q)``: the framework paper's 3-D distance error (§3.2, Alg. 1 step 4) with the
        obstacle constraint as a penalty on the sphere model's conservative clearance ``d``
        (never more than Drake's distance), plus the optional terms of this problem.
        """
        Q = np.asarray(Q, dtype=float)
        need_jac = self.manipulability_weight > 0
        if need_jac:
            X_WE, J = self.robot.batch.fk_jacobian(Q, self.frame)
        else:
            X_WE = self.robot.batch.fk(Q, self.frame)
        f = np.linalg.norm(X_WE[:, :3, 3] - self.p_WT, axis=1)
        if self.R_WT is not None and self.orientation_weight > 0:
            f += self.orientation_weight * rotation_angle(X_WE[:, :3, :3], self.R_WT)
        if self.scene is not None and self.scene.obstacles and self.collision_weight > 0:
            violation = self.clearance - self.scene.batch_min_distance(Q)
            f += self.collision_weight * np.maximum(violation, 0.0)
        if self.q_ref is not None and self.ref_weight > 0:
            f += self.ref_weight * np.linalg.norm(Q - self.q_ref, axis=1)
        if need_jac:
            Jv = J[:, 3:, :]
            det = np.linalg.det(Jv @ np.swapaxes(Jv, 1, 2))
            f -= self.manipulability_weight * np.sqrt(np.maximum(det, 0.0))
        return f

    __call__ = objective

    def __repr__(self) -> str:
        kind = "pose" if self.full_pose else "position"
        return (f"IKProblem({self.robot.name!r}, {kind} {np.round(self.p_WT, 4).tolist()}, "
                f"tol={self.position_tolerance:g} m/{self.orientation_tolerance:g} rad)")
