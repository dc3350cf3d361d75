"""``MotionResult``: one answer of :func:`drake_mh.planning.solve_motion`, verified."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class MotionResult:
    """A planned motion and its verdict, the same for every method.

    The motion is the piecewise-linear joint-space path through ``path``'s rows; ``trajectory``
    is that path retimed under the robot's limits (toppra through the waypoints where its
    spline is certified clear too, otherwise ruckig, which stops at every waypoint and follows
    the straight segments exactly).

    Attributes:
        method: the planner's name.
        success: verified (:mod:`drake_mh.planning.verify`): limits, start, goal, the whole
            motion certified collision-free, a certified trajectory. Never a solver's flag.
        path: ``(M, nq)`` waypoints [rad] (``M = 1`` when the start is the goal), or ``None``
            when the method found nothing.
        message: why it failed, or a summary.
        planning_time: wall-clock seconds of planning (neither goal IK nor verification).
        cpu_time: CPU seconds of planning.
        verify_time: wall-clock seconds of the verification and retiming (its parts:
            ``info["verify_parts"]``, :data:`drake_mh.planning.verify.VERIFY_PARTS`).
        min_clearance: certified lower bound of the obstacle clearance along the executed
            motion [m] (NaN when not certified).
        path_length: ``Σ ||q_{i+1} - q_i||`` [rad].
        trajectory: the retimed :class:`drake_mh.trajectories.Trajectory` (``None`` if none;
            a stationary one of zero duration, ``method == "stationary"``, when the start is the
            goal).
        duration: its duration [s] (NaN if none).
        max_jerk: largest joint jerk along it [rad/s³] (the certificate's bound, exact for
            ruckig's piecewise-constant jerk; ``inf`` at toppra's acceleration steps; NaN if no
            trajectory).
        jerk_limited: whether the trajectory is certified within the robot's declared jerk
            limits (``None``: no trajectory, or the robot declares none). toppra's are not;
            ``retime="ruckig"`` gives jerk-limited ones.
        limits: the limits the trajectory enforces, each with its source (declared by the
            model, set by the user or a limits file, derived, default):
            :class:`~drake_mh.robot.limits.JointLimits` (``print(result.limits.table())``;
            ``None`` without a trajectory).
        goal_index: which goal configuration the path reaches (pose goals: of the IK answers).
        goal_time: seconds spent on the goal configurations of a pose goal (0 when cached
            from an earlier method on the same problem, or for configuration goals).
        seed: the seed the method ran with.
        info: method-specific data (tree sizes, evaluations, ...).
    """

    method: str
    success: bool = False
    path: np.ndarray | None = None
    message: str = ""
    planning_time: float = float("nan")
    cpu_time: float = float("nan")
    verify_time: float = float("nan")
    min_clearance: float = float("nan")
    path_length: float = float("nan")
    trajectory: object = None
    duration: float = float("nan")
    max_jerk: float = float("nan")
    jerk_limited: bool | None = None
    limits: object = None
    goal_index: int | None = None
    goal_time: float = 0.0
    seed: object = None
    info: dict = field(default_factory=dict)

    def record(self) -> dict:
        """The scalar fields, for studies."""
        return {"method": self.method, "success": bool(self.success), "planning_time": self.planning_time,
                "cpu_time": self.cpu_time, "verify_time": self.verify_time, "min_clearance": self.min_clearance,
                "path_length": self.path_length, "duration": self.duration, "max_jerk": self.max_jerk,
                "jerk_limited": self.jerk_limited,
                "waypoints": 0 if self.path is None else int(len(self.path)), "message": self.message}

    def __repr__(self) -> str:
        if not self.success:
            return (f"MotionResult({self.method}: not verified (planning took {self.planning_time * 1e3:.2f} ms): "
                    f"{self.message})")
        return (f"MotionResult({self.method}: {len(self.path)} waypoints, planned in {self.planning_time * 1e3:.2f} ms, "
                f"path {self.path_length:.3f} rad, {self.duration:.2f} s retimed, certified clearance "
                f"{self.min_clearance * 1e3:.1f} mm)")
