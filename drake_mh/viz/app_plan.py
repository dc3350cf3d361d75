"""Point-to-point motion planning in the planner app: plan from where the arm is, then move.

The app's section "8 · Plan a motion" (:data:`drake_mh.viz.app_controls.SECTIONS`):

* "Plan to goal pose": the end effector to the point of the sliders "Goal X/Y/Z [m]" (drawn as
  a teal target with a triad), keeping the tool's current orientation: a pose goal of
  :class:`drake_mh.planning.MotionProblem`, whose goal configurations come from collision-free
  IK. Meshcat reports no clicks or drags in its 3-D view to Drake, so the target is dragged
  with these sliders;
* "Plan to goal joints": to the configuration of the sliders "Goal joint 1..n" (one per joint
  of the loaded robot, within its limits; shown as a blue ghost of the robot once they move);
* "Next planner" cycles :func:`drake_mh.planning.available_motion_methods` (default
  ``rrt_connect_smooth``), the slider "Plan timeout [s]" bounds planning.

:func:`drake_mh.planning.solve_motion` runs in a background thread, so the page stays live and
the status counts the seconds; meanwhile "Stop" cancels (the planner's answer is dropped when
it comes), the other buttons and the sliders are answered when planning ends, and nothing else
touches the robot or the scene. A verified result
(the whole motion certified collision-free, the retimed trajectory certified) is then played
along its retimed trajectory, and the status gives the method, the planning time and the
certified minimum clearance. Anything else leaves the robot where it was and says why: no
collision-free goal, no path within the timeout, or a path that failed the certification.
The robot never moves along an uncertified motion: "Stop" halts it on the motion, and moving the
obstacle (during planning or while it moves) halts it too, as the rest of the motion was
certified for the obstacle's old place only.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from drake_mh.errors import DrakeMhError, InvalidArgument
from drake_mh.viz.app_controls import SliderSpec, joint_slider_name

__all__ = ["AppPlanner", "DEFAULT_PLAN_METHODS", "check_plan_settings", "default_plan_method"]

DEFAULT_PLAN_METHODS = ("rrt_connect_smooth", "rrt_connect")
"""The first of these that is registered is the default planner."""
GOAL_COLOUR = (0.0, 0.75, 0.8, 0.9)
"""The goal point (teal, with a triad): the path's stop points are green."""
GOAL_GHOST_COLOUR = (0.3, 0.55, 1.0, 0.25)
PLAN_PATH_COLOUR = (0.95, 0.6, 0.05, 1.0)


def default_plan_method() -> str:
    """``rrt_connect_smooth`` (else ``rrt_connect``, else the first registered planner)."""
    from drake_mh.planning import available_motion_methods

    methods = available_motion_methods()
    return next((m for m in DEFAULT_PLAN_METHODS if m in methods), next(iter(methods)))


def check_plan_settings(method, timeout, goal, clearance) -> None:
    """Checks the app's planning settings (``AppConfig``'s ``plan_*`` fields).

    Raises:
        UnknownMethod: ``method`` is not a registered planner.
        InvalidArgument: timeout not in (0, 600] s, goal not 3 finite numbers, clearance < 0.
    """
    from drake_mh.planning import available_motion_methods

    if method is not None and method not in available_motion_methods():
        from drake_mh.errors import UnknownMethod

        raise UnknownMethod(method, list(available_motion_methods()), what="motion planning method")
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 < timeout <= 600:
        raise InvalidArgument(f"plan_timeout must be a number of seconds in (0, 600], got {timeout!r}")
    if goal is not None:
        g = np.asarray(goal, dtype=float) if not isinstance(goal, str) else np.zeros(0)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InvalidArgument(f"goal must be a point (x, y, z) [m], got {goal!r}")
    if isinstance(clearance, bool) or not isinstance(clearance, (int, float)) or not 0 <= clearance < 1:
        raise InvalidArgument(f"plan_clearance must be a distance in [0, 1) m, got {clearance!r}")


class AppPlanner:
    """The app's planning action and the playback of its certified motion (module docstring).

    Args:
        app: the :class:`drake_mh.viz.app.PlannerApp` (its robot, scene, view, controls).
    """

    def __init__(self, app):
        from drake_mh.planning import available_motion_methods

        config = app.config
        self.app = app
        self.methods = list(available_motion_methods())
        self.method = config.plan_method or default_plan_method()
        self.timeout = float(config.plan_timeout)
        self.clearance = float(config.plan_clearance)
        self.goal_p = np.array(config.goal if config.goal is not None else config.points[1], dtype=float)
        self.goal_q = None
        self.joint_sliders: list[str] = []
        self.problem = None
        self.result = None
        self.kind = None
        self.t = 0.0
        self._thread = None
        self._answer = None
        self._started = 0.0
        self.last: dict | None = None
        self.attempts = 0
        self.goal_time = 0.0
        self.ghost = False
        self.cancelled = False
        self.deferred: list[str] = []

    def sliders(self) -> list[SliderSpec]:
        """The fixed sliders (goal point, timeout); the joint sliders follow the robot."""
        reach = 1.5
        p = self.goal_p
        return [SliderSpec("Plan timeout [s]", 0.5, 30.0, 0.5, min(self.timeout, 30.0)),
                *(SliderSpec(f"Goal {a} [m]", -reach, reach, 0.01, p[i]) for i, a in enumerate("XYZ"))]

    # --- robot and drawing ------------------------------------------------------------------

    def robot_loaded(self) -> None:
        """A robot was loaded: its joint sliders replace the last robot's (goal: its home, or ``goal_q``)."""
        robot = self.app.robot
        controls = self.app.controls
        for name in self.joint_sliders:
            controls.remove_slider(name)
        self.goal_q = robot.home.copy()
        given = self.app.config.goal_q
        if given is not None and self.app.robot_index == 0:
            self.goal_q = robot.check_q(given, "goal_q").copy()
            outside = np.flatnonzero((self.goal_q < robot.lower) | (self.goal_q > robot.upper))
            if outside.size:
                j = int(outside[0])
                raise InvalidArgument(f"goal_q: joint {robot.joint_names[j]!r} = {self.goal_q[j]:.6g} is outside its "
                                      f"limits [{robot.lower[j]:.6g}, {robot.upper[j]:.6g}]")
        self.joint_sliders = []
        for i in range(robot.nq):
            low, high = (float(np.clip(v, -2 * np.pi, 2 * np.pi)) for v in (robot.lower[i], robot.upper[i]))
            name = joint_slider_name(i)
            controls.add_slider(SliderSpec(name, low, high, 0.01, float(np.clip(self.goal_q[i], low, high))))
            # the slider shows the value rounded to its step; the goal keeps it exactly until it moves
            self.joint_sliders.append(name)
        self.result = self.problem = None
        self.t = 0.0
        self.ghost = given is not None and self.app.robot_index == 0

    def draw(self) -> None:
        """Draws the goal point (with the tool's current orientation) and the goal configuration."""
        view = self.app.view
        view.add_target(self._goal_pose(), "goal", radius=0.02, colour=GOAL_COLOUR)
        if self.goal_q is not None and self.ghost:
            view.add_ghost(self.goal_q, "goal", colour=GOAL_GHOST_COLOUR)

    def _goal_pose(self) -> np.ndarray:
        X = np.array(self.app.robot.fk(self.app.view.q), dtype=float)
        X[:3, 3] = self.goal_p
        return X

    # --- controls ------------------------------------------------------------------------------

    def next_method(self) -> None:
        """'Next planner'."""
        self.method = self.methods[(self.methods.index(self.method) + 1) % len(self.methods)]
        self.app.message = f"planner {self.method} (used by the next Plan)"

    def sliders_changed(self, changed: dict) -> None:
        """Goal and timeout sliders moved: new goal (drawn), new timeout."""
        if "Plan timeout [s]" in changed:
            self.timeout = float(changed["Plan timeout [s]"])
        moved = [a for a in "XYZ" if f"Goal {a} [m]" in changed]
        for axis, a in enumerate("XYZ"):
            if a in moved:
                self.goal_p[axis] = changed[f"Goal {a} [m]"]
        joints = [i for i, name in enumerate(self.joint_sliders) if name in changed]
        for i in joints:
            self.goal_q[i] = changed[self.joint_sliders[i]]
        self.ghost = self.ghost or bool(joints)
        if moved or joints:
            self.draw()

    # --- planning -------------------------------------------------------------------------------

    @property
    def busy(self) -> bool:
        """Planning in the background."""
        return self._thread is not None

    def start(self, kind: str, wait: bool = False) -> bool:
        """'Plan to goal pose' (``kind="pose"``) or 'Plan to goal joints' (``"joints"``) from the
        configuration the robot is shown at; returns whether planning started.

        Args:
            kind: ``"pose"`` or ``"joints"``.
            wait: plan in this thread (the console's ``--plan``); else in a background thread
                that :meth:`poll` collects.
        """
        from drake_mh.planning import MotionProblem

        app = self.app
        if kind not in ("pose", "joints"):
            raise InvalidArgument(f"kind must be 'pose' or 'joints', got {kind!r}")
        app.mode = "idle"  # a running follower stops where it is; so does a planned motion
        q_start = app.view.q.copy()
        goal = self._goal_pose() if kind == "pose" else self.goal_q.copy()
        self.kind, self.result, self.t = kind, None, 0.0
        self.attempts += 1
        try:
            self.problem = MotionProblem(app.robot, app.scene, q_start, goal, clearance=self.clearance,
                                         name=f"app: to the goal {kind}")
        except DrakeMhError as exc:
            self._failed(f"cannot plan to the goal {kind}: {exc}")
            return False
        self._answer, self.cancelled = None, False
        self._started = time.monotonic()
        app.view.meshcat.Delete(f"{app.view.prefix}/paths/planned")  # the last motion's path
        if wait:
            self._plan(self.problem, self.method, self.timeout)
            self._thread = True
            self.poll()
            return True
        self._thread = threading.Thread(target=self._plan, args=(self.problem, self.method, self.timeout),
                                        name="drake-mh-app-plan", daemon=True)
        app.mode = "planning"
        app.message = f"planning with {self.method} to the goal {kind} (timeout {self.timeout:g} s)"
        self._thread.start()
        return True

    def _plan(self, problem, method: str, timeout: float) -> None:
        """The background work: goal configurations (pose goals), then solve_motion."""
        from drake_mh.errors import InvalidMotionProblem
        from drake_mh.planning import goal_configurations, solve_motion

        try:
            started = time.perf_counter()
            deadline = started + timeout  # one limit for the goal IK and the planning
            try:
                goal_configurations(problem, count=1, timeout=max(0.3, timeout / 3), deadline=deadline)
            except InvalidMotionProblem as exc:
                self._answer = ("no goal", str(exc))
                return
            finally:
                self.goal_time = time.perf_counter() - started
            self._answer = ("result", solve_motion(problem, method, seed=self.attempts,
                                                   timeout=max(deadline - time.perf_counter(), 1e-3)))
        except Exception as exc:  # noqa: BLE001 - reported in the status; the app goes on
            self._answer = ("error", f"{type(exc).__name__}: {exc}")

    def poll(self, clicked=()) -> None:
        """Collects a finished planning (else updates the status with the seconds spent).

        Args:
            clicked: buttons clicked meanwhile: "Stop" cancels (the planner's answer, when it
                comes, is dropped), the others wait in :attr:`deferred` until planning ends.
        """
        app = self.app
        if self._thread is None:
            return
        for name in clicked:
            if name == "Stop":
                self.cancelled = True
            else:
                self.deferred.append(name)
        if isinstance(self._thread, threading.Thread):
            if self._thread.is_alive():
                waiting = ("cancelled: the planner's answer will be dropped" if self.cancelled
                           else "the other controls answer after")
                app.message = (f"planning with {self.method} to the goal {self.kind}: "
                               f"{time.monotonic() - self._started:.1f} s of {self.timeout:g} s ({waiting})")
                return
            self._thread.join()
        self._thread = None
        app.mode = "idle"
        what, answer = self._answer or ("error", "planning ended without an answer")
        if self.cancelled:
            return self._failed("planning cancelled with Stop")
        if what == "no goal":
            return self._failed(f"no collision-free goal: {answer}")
        if what == "error":
            return self._failed(f"planning failed: {answer}")
        self._finish(answer)

    def dispatch(self, clicked, handle) -> None:
        """Runs ``handle`` on the clicks that waited, then on ``clicked``, in order; once one starts
        planning, the rest wait for it to end (nothing may change the robot or the scene meanwhile)."""
        queue, self.deferred = [*self.deferred, *clicked], []
        for i, name in enumerate(queue):
            if self.busy:
                self.deferred = queue[i:]
                return
            handle(name)

    def _finish(self, result) -> None:
        from drake_mh.viz.motion import clearance_words, motion_caption

        self.result = result
        timed_out = self.goal_time + result.planning_time >= 0.98 * self.timeout
        self.last = {"attempt": self.attempts, "success": bool(result.success), "method": result.method,
                     "goal": self.kind,
                     "planning_time": result.planning_time, "goal_time": self.goal_time,
                     "min_clearance": float(result.min_clearance) if result.success else None,
                     "duration": float(result.duration) if result.success else None,
                     "waypoints": None if result.path is None else int(len(result.path)), "message": result.message}
        if not result.success:
            if result.path is None:
                why = (f"no path within the timeout ({self.timeout:g} s)" if timed_out
                       else f"no path found ({result.message or 'the planner gave up'})")
            else:
                why = f"the path found is not certified ({result.message})"
            self.result = None
            return self._failed(f"{result.method}: {why}")
        self.last["caption"] = motion_caption(result, self.app.scene)
        Q = result.trajectory.position(np.linspace(result.trajectory.start_time, result.trajectory.end_time, 60))
        self.app.view.add_ee_path(Q, "planned", colour=PLAN_PATH_COLOUR)
        self.t = 0.0
        self.app.mode = "plan"
        ik = f" (goal IK {self.goal_time:.2f} s)" if self.kind == "pose" else ""
        self.app.message = (f"moving to the goal {self.kind}: planned with {result.method} in "
                            f"{result.planning_time * 1e3:.1f} ms{ik}, {clearance_words(result, self.app.scene)}, "
                            f"{result.duration:.2f} s motion")

    def _failed(self, message: str) -> None:
        """Planning gave no certified motion: the robot stays where it is."""
        self.app.mode = "idle"
        self.app.message = f"{message}; the robot stays where it is"
        record = self.last if self.last is not None and self.last.get("attempt") == self.attempts else {}
        self.last = {**record, "attempt": self.attempts, "success": False, "goal": self.kind,
                     "method": self.method, "message": self.app.message}

    # --- playback ------------------------------------------------------------------------------

    def advance(self, dt: float) -> None:
        """Poses the robot ``dt`` seconds further along the certified trajectory."""
        traj = self.result.trajectory
        self.t = min(self.t + dt, traj.duration)
        q = traj.position(np.array([traj.start_time + self.t]))[0]
        if self.t >= traj.duration:
            q = np.asarray(self.result.path[-1], dtype=float)  # the verified goal, exactly
        self.app.view.set_q(q)
        if self.t >= traj.duration:
            self.app.mode = "idle"
            self.app.message = f"at the goal {self.kind}: {self.last['caption']}"
            self.draw()  # the goal point's triad: the orientation a pose goal now keeps

    def halt(self, why: str) -> str:
        """Stops a planned motion where the robot is; returns the message ("" if none was moving)."""
        if self.app.mode != "plan":
            return ""
        self.app.mode = "idle"
        self.app.message = f"planned motion stopped {self.t:.2f} s in: {why}"
        self.result = None
        return self.app.message

    def state(self) -> dict:
        """The planning part of the app's state."""
        return {"plan_method": self.method, "plan_timeout": self.timeout, "plan_goal_position": self.goal_p.tolist(),
                "plan_goal_q": None if self.goal_q is None else self.goal_q.tolist(), "planning": self.busy,
                "plan": self.last, "plan_t": self.t}
