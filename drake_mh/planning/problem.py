"""``MotionProblem``: move a robot from a configuration to a goal without hitting anything.

The goal is a configuration ``(nq,)``, several configurations ``(M, nq)`` (any one will do),
or an end-effector pose ``X_WG (4, 4)``, whose goal configurations then come from
collision-free IK (:func:`drake_mh.solve_ik`, verified with Drake) at solve time.

Every method of :func:`drake_mh.planning.solve_motion` reads the same problem and is verified
the same way (:mod:`drake_mh.planning.verify`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_mh.errors import DrakeMhError, InvalidMotionProblem

POSE_POSITION_TOLERANCE = 1e-3
"""[m] reaching a goal pose: as :class:`drake_mh.ik.IKProblem`'s default."""

POSE_ORIENTATION_TOLERANCE = 1e-2
"""[rad] reaching a goal pose: as :class:`drake_mh.ik.IKProblem`'s default."""


def _numbers(value, what: str) -> np.ndarray:
    """``value`` as a real float array (complex values refused, not truncated to their real part)."""
    try:
        complex_ = np.iscomplexobj(value)
        array = None if complex_ else np.asarray(value, dtype=float)
    except (TypeError, ValueError):  # text, None, ragged nested lists
        raise InvalidMotionProblem(f"{what} must be an array of numbers, got {str(value)[:80]!r}") from None
    if complex_:
        raise InvalidMotionProblem(f"{what} must be real numbers, got complex values")
    return array


@dataclass(frozen=True, eq=False)
class MotionProblem:
    """A point-to-point motion among the obstacles of a scene.

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        scene: a :class:`drake_mh.scene.Scene` of that robot (its obstacles as they are; with
            ``self_collision`` its link pairs too).
        q_start: ``(nq,)`` start configuration, inside the limits and collision-free.
        goal: ``(nq,)`` configuration, ``(M, nq)`` configurations (any one), or ``X_WG (4, 4)``
            pose of the end effector (``frame``).
        clearance: required distance to every obstacle along the whole motion [m].
        self_clearance: required distance between checked link pairs [m].
        frame: end-effector frame for a pose goal (default ``robot.ee_frame_name``).
        name: label for reports.

    The arrays are copied: changing the caller's arrays afterwards changes nothing here. A
    start that already reaches the goal is a valid problem: :func:`~drake_mh.planning.solve_motion`
    answers it with the one-waypoint path and a stationary trajectory of zero duration. The scene
    is the caller's and may change; ``solve_motion`` checks start and goals against it as it is.

    Raises:
        InvalidMotionProblem: any argument ill-formed (complex, ragged or text arrays
            included), outside the limits, or a start / every goal configuration in collision
            (measured with the sphere model: certified free is what the planners need).
    """

    robot: object
    scene: object
    q_start: np.ndarray
    goal: np.ndarray
    clearance: float = 0.0
    self_clearance: float = 0.0
    frame: str | None = None
    name: str = ""
    goal_configurations: np.ndarray | None = field(init=False, default=None)
    goal_pose: np.ndarray | None = field(init=False, default=None)

    def __post_init__(self):
        from drake_mh.robot import Robot
        from drake_mh.scene import Scene
        from drake_mh.scene.segments import check_clearance

        if not isinstance(self.robot, Robot):
            raise InvalidMotionProblem(f"robot must be a drake_mh Robot (drake_mh.load_robot), got {type(self.robot).__name__}")
        if not isinstance(self.scene, Scene) or self.scene.robot is not self.robot:
            raise InvalidMotionProblem("scene must be a drake_mh.scene.Scene of this robot: Scene(robot), then scene.add(...)")
        try:
            clearance = check_clearance(self.clearance, "clearance")
            self_clearance = check_clearance(self.self_clearance, "self_clearance")
        except DrakeMhError as exc:
            raise InvalidMotionProblem(str(exc)) from None
        object.__setattr__(self, "clearance", clearance)
        object.__setattr__(self, "self_clearance", self_clearance)
        q_start = self._configurations(self.q_start, "q_start")
        if q_start.shape[0] != 1:
            raise InvalidMotionProblem(f"q_start must be one configuration ({self.robot.nq},), got {q_start.shape[0]}")
        object.__setattr__(self, "q_start", q_start[0])
        if not self.is_free(q_start[0]):
            raise InvalidMotionProblem(
                f"q_start is in collision or closer than the clearance ({clearance} m to obstacles, {self_clearance} "
                f"m between links) under the sphere model; exact distance {self.scene.min_distance(q_start[0]):.4f} m. "
                "Move the start, lower the clearance, or move the obstacles")
        goal = _numbers(self.goal, "goal")
        if goal.shape == (4, 4) and self.robot.nq != 4:
            if not np.all(np.isfinite(goal)) or not np.allclose(goal[3], [0, 0, 0, 1]):
                raise InvalidMotionProblem("a goal pose must be a finite homogeneous transform X_WG (4, 4)")
            R = goal[:3, :3]
            if not np.allclose(R.T @ R, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
                raise InvalidMotionProblem("the goal pose's rotation X_WG[:3, :3] must be a rotation matrix")
            object.__setattr__(self, "goal_pose", goal.copy())
            object.__setattr__(self, "goal", goal.copy())
            self.robot.batch.frame_arrays(self.frame)  # FrameNotFound for an unknown frame
            return
        G = self._configurations(goal, "goal")
        free = self.scene.collision_free(G, clearance, self_clearance)
        if not np.any(free):
            raise InvalidMotionProblem(
                f"every goal configuration ({len(G)}) is in collision or closer than the clearance under the sphere "
                "model; move the goal or the obstacles, or lower the clearance")
        object.__setattr__(self, "goal", G[0] if goal.ndim == 1 else G)
        object.__setattr__(self, "goal_configurations", G[free])

    def _configurations(self, value, what: str) -> np.ndarray:
        """``value`` as a fresh ``(N, nq)`` array (a copy: the caller's array may change later)."""
        robot = self.robot
        try:
            Q = np.array(robot.check_Q(np.atleast_2d(_numbers(value, what)), what), dtype=float, order="C")
        except DrakeMhError as exc:
            raise InvalidMotionProblem(f"{what} must be configuration(s) of {robot.nq} joints [rad or m]: {exc}") from None
        outside = (Q < robot.lower - 1e-12) | (Q > robot.upper + 1e-12)
        if np.any(outside):
            row, j = np.argwhere(outside)[0]
            raise InvalidMotionProblem(
                f"{what}: joint {robot.joint_names[j]!r} = {Q[row, j]:.6g} is outside its limits "
                f"[{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]")
        return np.ascontiguousarray(Q)

    def blocked_now(self, goals: np.ndarray | None = None) -> str:
        """Why planning cannot start in the scene as it is now ("" when it can): the start, or
        every row of ``goals``, no longer certified free (an obstacle added or moved since the
        problem was built)."""
        if not self.is_free(self.q_start):
            return (f"q_start is now in collision or closer than the clearance ({self.clearance} m) under the sphere "
                    "model: the scene changed after the problem was built; move the obstacle or the start")
        if goals is not None and not np.any(self.is_free(goals)):
            return (f"every goal configuration ({len(goals)}) is now in collision or closer than the clearance "
                    f"({self.clearance} m) under the sphere model: the scene changed after the problem was built; "
                    "move the obstacle or the goal")
        return ""

    def is_free(self, Q) -> np.ndarray | bool:
        """Certified free under the sphere model with this problem's clearances."""
        return self.scene.collision_free(Q, self.clearance, self.self_clearance)

    @property
    def nq(self) -> int:
        return self.robot.nq

    def __repr__(self) -> str:
        goal = ("pose" if self.goal_pose is not None else "?" if self.goal_configurations is None
                else f"{len(self.goal_configurations)} configuration(s)")
        label = f"{self.name!r}, " if self.name else ""
        return (f"MotionProblem({label}{self.robot.name}, {len(self.scene.obstacles)} obstacles, goal: {goal}, "
                f"clearance {self.clearance} m)")
