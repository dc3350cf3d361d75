"""The interactive planner app (framework paper §4, GUI of Table 1) in the browser with Meshcat.

Table 1's parts and where they are here (details in ``docs/app.md``):

* part 1 (robot, algorithm, obstacle): ``--robot`` / ``--method`` / ``--no-obstacle``; the
  buttons "Next robot" and "Next algorithm" cycle the choices (Meshcat has no drop-down);
* part 2 (path: start / via / end points, number of points): "Edit next point" selects start,
  via 1, via 2 or end, the sliders "Point X/Y/Z" move it, the slider "Points in path";
* part 3 (simulation window): the Meshcat view; "Show environment" draws path, robot, obstacle;
* part 4 (IK solver): "Generate / Regenerate solutions" (§3.3), "Test run" (play once);
* parts 5, 7: "Run" (loops on a closed path) and "Stop";
* part 6 (obstacle position): sliders "Obstacle X/Y/Z" (and radius) move the obstacle live; the
  follower regenerates (§3.4.1) or re-plans (§3.4.2) at once (:mod:`drake_mh.reactive.follower`);
* (beyond Table 1) "8 · Plan a motion": point-to-point planning from where the arm is to a goal
  pose or configuration with any :func:`drake_mh.planning.available_motion_methods`, in the
  background, then the certified motion is played (:mod:`drake_mh.viz.app_plan`).

The robot moves only along certified motions: the follower certifies the motion between two
path points against the obstacle as it is when the arm starts it (a detour through via
configurations where the straight joint-space line is not certified); without one the arm stops
and the status says why. The state reports whether the motion ahead is certified, its certified
clearance, the clearance certified along what the arm executed, and the detours.

A status line ("Setup: ..." / "Status: ...", inert buttons at the bottom of the panel: Meshcat
has no text element) reports what happened. ``status_file`` receives the same state as JSON
(rewritten atomically on every change) for scripts and tests; ``max_seconds`` ends the loop.

The page a user opens is the app's own (:mod:`drake_mh.viz.app_page`): the status box and the
controls first, in Table 1's order, and Meshcat's 3-D view beside them (Meshcat's own panel
lists the controls after its Scene / Animations folders, below the fold). The obstacle is drawn
translucent red, distinct from the (orange) robots. :func:`drake_mh.cli.app.run_app` is ``drake-mh app``: it
prints the page's URL, runs the loop, and ends with its own "app stopped" line on Ctrl-C.

Everything runs in the thread that created Meshcat (Drake requires it): one loop polls the
controls, moves the obstacle, regenerates and poses the robot at ``fps``. Generation blocks
the loop (the status shows the progress); the browser stays connected.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import numbers
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.viz.app_controls import MAX_GOAL_JOINTS, SECTIONS, Controls, SliderSpec, joint_slider_name
from drake_mh.viz.app_plan import AppPlanner, check_plan_settings

logger = logging.getLogger(__name__)

__all__ = ["AppConfig", "PlannerApp", "POINT_NAMES"]

POINT_NAMES = ("start", "via 1", "via 2", "end")

OBSTACLE_COLOUR = (0.9, 0.08, 0.08, 0.4)
"""Translucent red ``(r, g, b, a)``: the bundled robots are orange, the path blue, the points green."""
EDITED_POINT_COLOUR = (0.55, 0.1, 0.95, 1.0)
"""The path point the Point X/Y/Z sliders edit (violet); the others are green."""
POINT_COLOUR = (0.1, 0.75, 0.2, 0.9)


@dataclass(frozen=True)
class AppConfig:
    """Start-up settings of the app (the command line's options).

    Attributes:
        robots: robot names the "Next robot" button cycles through (the first is loaded).
        method: IK / planner algorithm (any of :func:`drake_mh.ik.available_ik_methods`).
        points: ``((x, y, z) * 4)`` start, via 1, via 2, end [m] (default Table 3: a closed loop).
        n_points: points in the path (Table 3: 50).
        obstacle: ``(x, y, z)`` [m] or ``None`` for no obstacle (default (0.2, 0.2, 0.6)).
        obstacle_radius: [m] of the spherical obstacle (default 0.2, as the scenario).
        seed: seed of generation and regeneration; budget: per IK solve (``None``: default).
        fps: frame rate of the loop [Hz]; speed: playback speed (1 = the path's own timing).
        port: Meshcat port (``None``: first free from 7000; 0: any); the app's page takes the
            first free port after Meshcat's (0: any).
        status_file: JSON status written on every change (``None``: none).
        plan_method: motion planner of "Plan to goal ..." (``None``: ``rrt_connect_smooth``).
        plan_timeout: [s] planning limit (the slider "Plan timeout [s]"); goal: ``(x, y, z)`` [m]
            of the goal point (``None``: via point 1); goal_q: goal configuration of the first robot
            (``None``: its home); plan_clearance: [m] required along motions.
        scene: a scene file whose obstacles stay put beside the movable one (``None``: none;
            :meth:`drake_mh.scene.Scene.load`); scene_packages: ``{name: folder}`` for its
            ``package://`` names.
    """

    robots: tuple = ("seed000_6dof", "panda")
    method: str = "e3gsa"
    points: tuple = ((0.2, 0.8, 0.3), (1.0, 0.2, 0.2), (0.5, 0.4, 0.1), (0.2, 0.8, 0.3))
    n_points: int = 50
    obstacle: tuple | None = (0.2, 0.2, 0.6)
    obstacle_radius: float = 0.2
    seed: int = 0
    budget: int | None = None
    fps: float = 30.0
    speed: float = 1.0
    port: int | None = None
    status_file: str | None = None
    plan_method: str | None = None
    plan_timeout: float = 5.0
    goal: tuple | None = None
    goal_q: tuple | None = None
    plan_clearance: float = 0.0
    scene: str | None = None
    scene_packages: dict | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        from drake_mh.ik import available_ik_methods

        if self.method.lower() not in available_ik_methods():
            from drake_mh.errors import UnknownMethod

            raise UnknownMethod(self.method, available_ik_methods(), what="IK method")
        P = np.asarray(self.points, dtype=float)
        if P.shape != (4, 3) or not np.all(np.isfinite(P)):
            raise InvalidArgument(f"points must be start, via 1, via 2, end: 4 finite (x, y, z) [m], got {P.shape}")
        if isinstance(self.n_points, bool) or not isinstance(self.n_points, numbers.Integral) \
                or not 4 <= self.n_points <= 500:
            raise InvalidArgument(f"n_points must be an integer in [4, 500], got {self.n_points!r}")
        real = lambda value: not isinstance(value, bool) and isinstance(value, numbers.Real) and np.isfinite(value)
        if not (real(self.fps) and 1 <= self.fps <= 120):
            raise InvalidArgument(f"fps must be in [1, 120] Hz, got {self.fps!r}")
        if not (real(self.speed) and self.speed > 0):
            raise InvalidArgument(f"speed must be > 0, got {self.speed!r}")
        if not (real(self.obstacle_radius) and self.obstacle_radius > 0):
            raise InvalidArgument(f"obstacle_radius must be a positive length [m], got {self.obstacle_radius!r}")
        if not self.robots:
            raise InvalidArgument("robots must name at least one robot (drake-mh robots lists them)")
        if isinstance(self.seed, bool) or not isinstance(self.seed, numbers.Integral) or self.seed < 0:
            raise InvalidArgument(f"seed must be an integer >= 0, got {self.seed!r}")
        if self.budget is not None and (isinstance(self.budget, bool) or not isinstance(self.budget, numbers.Integral)
                                        or self.budget < 1):
            raise InvalidArgument(f"budget must be an integer >= 1 (per IK solve) or None, got {self.budget!r}")
        if self.obstacle is not None:
            o = np.asarray(self.obstacle, dtype=float) if not isinstance(self.obstacle, str) else np.zeros(0)
            if o.shape != (3,) or not np.all(np.isfinite(o)):
                raise InvalidArgument(f"obstacle must be a point (x, y, z) [m] or None, got {self.obstacle!r}")
        check_plan_settings(self.plan_method, self.plan_timeout, self.goal, self.plan_clearance)


class PlannerApp:
    """The app: state, drawing and one loop (module docstring).

    Args:
        config: :class:`AppConfig`.
        meshcat: a Meshcat instance (default: this thread's localhost server).
        page: serve the app's page (:attr:`page_url`); ``False``: Meshcat's page only.
    """

    def __init__(self, config: AppConfig = AppConfig(), meshcat=None, page: bool = True):
        from drake_mh.ik import available_ik_methods
        from drake_mh.viz.server import get_meshcat

        self.config = config
        if meshcat is None:  # the app prints its own page's URL: no "open Meshcat" lines
            import pydrake.geometry  # noqa: F401 - pydrake ties the "drake" logger to Drake's on import

            drake_log = logging.getLogger("drake")
            level = drake_log.level
            drake_log.setLevel(max(logging.WARNING, drake_log.getEffectiveLevel()))
            try:
                meshcat = get_meshcat(config.port, announce=False)
            finally:
                drake_log.setLevel(level)
        self.meshcat = meshcat
        self.methods = available_ik_methods()
        self.method = config.method.lower()
        self.robot_index = 0
        self.points = np.array(config.points, dtype=float)
        self.n_points = int(config.n_points)
        self.edit = 0
        self.mode = "idle"          # idle | test | run
        self.t = 0.0                # time along the path [s]
        self.follower = None
        self.motion: dict = {}
        self._shown_motion = None   # (segment, chain) certified for display
        self.message = "ready: press Generate / Regenerate solutions"
        self.events = 0
        self.regenerated_total = 0
        self.last_event = ""
        self.frames = 0
        self.run_frames, self.run_time = 0, 0.0
        self.started = time.monotonic()
        self.clicks: dict[str, int] = {}
        self.controls, self.planner = None, AppPlanner(self)
        self.scene_file = None  # the --scene file's obstacles, read once, added to each robot's scene
        if config.scene is not None:
            from drake_mh.scene.files import read_scene

            self.scene_file = read_scene(config.scene, packages=config.scene_packages)
        self._load_robot()
        P = self.points
        o = config.obstacle if config.obstacle is not None else (0.5, 0.5, 0.5)
        reach = 1.5
        sliders = [
            SliderSpec("Point X [m]", -reach, reach, 0.01, P[0, 0]),
            SliderSpec("Point Y [m]", -reach, reach, 0.01, P[0, 1]),
            SliderSpec("Point Z [m]", -reach, reach, 0.01, P[0, 2]),
            SliderSpec("Points in path", 4, 200, 1, self.n_points),
            SliderSpec("Obstacle X [m]", -reach, reach, 0.01, o[0]),
            SliderSpec("Obstacle Y [m]", -reach, reach, 0.01, o[1]),
            SliderSpec("Obstacle Z [m]", -reach, reach, 0.01, o[2]),
            SliderSpec("Obstacle radius [m]", 0.01, 0.5, 0.01, config.obstacle_radius),
            *self.planner.sliders(),
        ]
        self.controls = Controls(self.meshcat, sliders)
        self.planner.robot_loaded()
        self.page = None
        if page:
            from drake_mh.viz.app_page import AppPage, page_html

            joints = [joint_slider_name(i) for i in range(MAX_GOAL_JOINTS)]
            html = page_html(self.meshcat.port(), SECTIONS, [s.name for s in sliders] + joints,
                             primary=("Generate / Regenerate solutions", "Run", "Plan to goal pose"),
                             wide=("Generate / Regenerate solutions",))
            self.page = AppPage(html, port=0 if config.port == 0 else None, first=self.meshcat.port() + 1)
        self.meshcat.SetCameraPose([1.25, -0.65, 0.85], [0.45, 0.35, 0.3])  # the Table 3 workspace, close up
        self.show_environment()

    @property
    def page_url(self) -> str:
        """URL of the app's page (controls and 3-D view), or Meshcat's when no page is served."""
        return self.page.url if self.page is not None else self.meshcat.web_url()

    def close(self) -> None:
        """Stops serving the page (Meshcat itself lives on with its thread)."""
        if self.page is not None:
            self.page.close()

    # --- model -----------------------------------------------------------------------------

    @property
    def robot_name(self) -> str:
        """The loaded robot's name."""
        return self.config.robots[self.robot_index]

    def _load_robot(self) -> None:
        import drake_mh
        from drake_mh.scene import Scene, Sphere
        from drake_mh.viz.view import View

        self.robot = drake_mh.load_robot(self.robot_name)
        self.scene = Scene(self.robot)
        if self.scene_file is not None:
            self.scene.load(self.scene_file)
        if self.config.obstacle is not None:
            radius = getattr(self, "_radius", self.config.obstacle_radius)
            position = getattr(self, "_obstacle_p", self.config.obstacle)
            self.scene.add("obstacle", Sphere(radius), position)
        self.view = View(self.robot, meshcat=self.meshcat)
        self._make_path()
        if self.controls is not None:
            self.planner.robot_loaded()

    def _make_path(self) -> None:
        from drake_mh.paths import trapezoidal_path

        points = self.points
        keep = np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > 1e-9])
        self.path = trapezoidal_path(points[keep], n_points=max(self.n_points, int(keep.sum())))
        self.follower = None

    def _follower_config(self):
        from drake_mh.reactive.follower import FollowerConfig

        return FollowerConfig(method=self.method, budget=self.config.budget)

    # --- drawing ---------------------------------------------------------------------------

    def show_environment(self) -> None:
        """Draws the path, its stop points, the obstacle, the planning goal and the robot where it is
        (Table 1 part 3)."""
        view = self.view
        view.add_obstacles(self.scene, colour=OBSTACLE_COLOUR)
        points = self.follower.points if self.follower is not None else self.path.points
        view.add_path(points, "path")
        for i, p in enumerate(self.points):
            view.add_target(p, f"point{i}", radius=0.025 if i == self.edit else 0.015,
                            colour=EDITED_POINT_COLOUR if i == self.edit else POINT_COLOUR)
        self.planner.draw()
        view.set_q(view.q)

    def _pose_along(self, t: float) -> bool:
        """Poses the robot at time ``t`` of the path along the certified motion between the points'
        solutions (straight in joint space, or a detour); returns ``False`` when the arm stopped:
        no certified motion to the next point (the status says why)."""
        from drake_mh.reactive.follower.detour import chain_durations

        f = self.follower
        times = self.path.times
        k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1))
        while f.index < k:
            before = f.index
            f.advance()
            if f.index == before:
                return self._halt()
        if k >= len(times) - 1:
            self.view.set_q(f.Q[-1])
            return True
        if self._shown_motion is None or self._shown_motion[0] != k:
            chain = f.next_motion()
            if chain is None:
                return self._halt()
            self._shown_motion = (k, chain)
        chain = self._shown_motion[1]
        s = float(np.clip((t - times[k]) / max(times[k + 1] - times[k], 1e-9), 0.0, 1.0))
        ends = np.concatenate([[0.0], np.cumsum(chain_durations(chain, 1.0))])
        i = int(np.clip(np.searchsorted(ends, s, side="right") - 1, 0, len(chain) - 2))
        u = (s - ends[i]) / max(ends[i + 1] - ends[i], 1e-12)
        self.view.set_q(chain[i] + np.clip(u, 0.0, 1.0) * (chain[i + 1] - chain[i]))
        return True

    def _halt(self) -> bool:
        self.view.set_q(self.follower.q)
        self.mode = "idle"
        self.message = f"{self.follower.halted}; move the obstacle or regenerate"
        self._update_motion()
        return False

    def _motion_words(self) -> str:
        m = self.motion
        if not m:
            return ""
        if m["motion_certified"]:
            clear = m["motion_min_clearance"]
            words = "; motion certified collision-free" + (f" (>= {clear:.3f} m)" if clear is not None else "")
        else:
            words = f"; NO certified motion on segments {m['motion_blocked']}"
        if m["detours_found"]:
            words += f", {m['detours_found']} detours"
        return words

    def _update_motion(self) -> None:
        """The verdict on the follower's motion (the app's result): ahead and executed."""
        f = self.follower
        self._shown_motion = None
        if f is None:
            self.motion = {}
            return
        cert = f.certify_remaining()
        executed = f.segment_lower[:f.index]
        self.motion = {
            "motion_certified": True if cert is None else cert.all_certified,
            "motion_min_clearance": None if cert is None or not cert.all_certified else float(cert.min_clearance),
            "motion_blocked": sorted(int(k) for k in f.blocked),
            "executed_min_clearance": float(np.min(executed)) if executed.size else None,
            "halted": f.halted,
            **f.detour_summary(),
        }

    # --- actions (buttons) -------------------------------------------------------------------

    def generate(self) -> None:
        """'Generate / Regenerate solutions': IK at every point with the chosen algorithm (§3.3)."""
        from drake_mh.reactive.follower import RegeneratingFollower

        self.mode = "idle"
        seed = self.config.seed + self.clicks.get("Generate / Regenerate solutions", 0)
        start = time.perf_counter()

        def progress(k, n):
            if k % 5 == 0 or k == n:
                self._status(f"generating with {self.method}: {k}/{n} points")

        self.follower = RegeneratingFollower.plan(self.robot, self.scene, self.path, self._follower_config(),
                                                  seed=seed, progress=progress)
        self.view.set_q(self.follower.q)
        took = time.perf_counter() - start
        failed = self.follower.plan_failed
        self._update_motion()
        self.message = (f"solutions generated with {self.method} in {took:.1f} s, largest joint step "
                        f"{self.follower.remaining_max_step():.3f} rad"
                        + (f"; NOT verified at points {failed.tolist()}" if failed.size else "; all verified")
                        + self._motion_words())
        self.show_environment()

    def play(self, mode: str) -> None:
        """'Test run' (once) or 'Run' (looping on a closed path) from the start."""
        if self.follower is None:
            self.message = "no solutions yet: press Generate / Regenerate solutions first"
            return
        self.follower.restart(0)
        self._shown_motion = None
        self.t = 0.0
        self.mode = mode
        self.run_frames, self.run_time = 0, 0.0
        self.message = "test run" if mode == "test" else "running: move the obstacle with its sliders"

    def stop(self) -> None:
        """'Stop' (a planned motion stops where the robot is)."""
        if self.planner.halt("stopped"):
            return
        self.mode = "idle"
        self.message = f"stopped at point {self.follower.index if self.follower else 0}"

    def next_robot(self) -> None:
        """'Next robot': loads the next robot of ``config.robots`` (the plan is discarded)."""
        self.robot_index = (self.robot_index + 1) % len(self.config.robots)
        self.mode = "idle"
        self._load_robot()
        self.show_environment()
        self.message = f"robot {self.robot_name} loaded: press Generate / Regenerate solutions"

    def next_algorithm(self) -> None:
        """'Next algorithm': the next IK method; regeneration uses it from now on."""
        self.method = self.methods[(self.methods.index(self.method) + 1) % len(self.methods)]
        if self.follower is not None:
            self.follower.config = dataclasses.replace(self.follower.config, method=self.method)
        self.message = f"algorithm {self.method} (used by the next generation and every regeneration)"

    def next_point(self) -> None:
        """'Edit next point': the Point X/Y/Z sliders now edit start / via 1 / via 2 / end."""
        self.edit = (self.edit + 1) % 4
        for axis, name in enumerate(("Point X [m]", "Point Y [m]", "Point Z [m]")):
            self.controls.set(name, self.points[self.edit, axis])
        self.show_environment()
        self.message = f"editing the {POINT_NAMES[self.edit]} point"

    # --- reactions (sliders) ------------------------------------------------------------------

    def move_obstacle(self, position=None, radius=None) -> None:
        """Moves (or resizes) the obstacle and lets the follower react (§3.4.1 / §3.4.2)."""
        from drake_mh.scene import Sphere

        if self.config.obstacle is None:
            self.message = "no obstacle (started with --no-obstacle)"
            return
        halted = self.planner.halt("the obstacle moved; the motion was certified for its old place only")
        if radius is not None:
            self._radius = float(radius)
            p = self.scene.obstacles["obstacle"].position
            self.scene.remove("obstacle")
            self.scene.add("obstacle", Sphere(self._radius), p)
            self.view.add_obstacles(self.scene, colour=OBSTACLE_COLOUR)
        if position is not None:
            self._obstacle_p = tuple(float(v) for v in position)
            self.scene.move("obstacle", position)
            self.view.update_obstacles(self.scene, colour=OBSTACLE_COLOUR)
        if self.follower is None:
            self.message = halted or "obstacle moved (no solutions yet)"
            return
        event = self.follower.react()
        if event.changed:
            self.events += 1
            self.regenerated_total += int(event.regenerated.size)
            self.last_event = event.summary()
            if event.replans:
                self.view.add_path(self.follower.points, "path")
        self._update_motion()
        self.message = (f"{halted}; " if halted else "") + event.summary() + self._motion_words()

    def edit_path(self, changed: dict) -> None:
        """A path slider moved: new path, solutions discarded."""
        for axis, name in enumerate(("Point X [m]", "Point Y [m]", "Point Z [m]")):
            if name in changed:
                self.points[self.edit, axis] = changed[name]
        if "Points in path" in changed:
            self.n_points = int(round(changed["Points in path"]))
        self.mode = "idle"
        self._make_path()
        self.show_environment()
        self.message = (f"path changed ({len(self.path.points)} points, {self.path.duration:.1f} s): "
                        "press Generate / Regenerate solutions")

    # --- loop -------------------------------------------------------------------------------

    def handle(self, name: str) -> None:
        """Runs the action of a clicked button."""
        self.clicks[name] = self.clicks.get(name, 0) + 1
        actions = {
            "Next robot": self.next_robot, "Next algorithm": self.next_algorithm, "Edit next point": self.next_point,
            "Show environment": self.show_environment, "Generate / Regenerate solutions": self.generate,
            "Test run": lambda: self.play("test"), "Run": lambda: self.play("run"), "Stop": self.stop,
            "Plan to goal pose": lambda: self.planner.start("pose"), "Next planner": self.planner.next_method,
            "Plan to goal joints": lambda: self.planner.start("joints"),
        }
        if name in actions:
            actions[name]()

    def tick(self, dt: float) -> None:
        """One frame: buttons, sliders, motion (while planning: only the status; the rest waits)."""
        if self.planner.busy:
            return self.planner.poll(self.controls.clicked())
        self.planner.dispatch(self.controls.clicked(), self.handle)
        if self.planner.busy:  # the scene stays as the planner sees it
            return
        changed = self.controls.changed()
        self.planner.sliders_changed(changed)
        if any(k.startswith("Point") for k in changed):
            self.edit_path(changed)
        moved = [changed.get(f"Obstacle {a} [m]") for a in "XYZ"]
        if any(v is not None for v in moved) or "Obstacle radius [m]" in changed:
            p = [self.controls.value(f"Obstacle {a} [m]") for a in "XYZ"]
            self.move_obstacle(p if any(v is not None for v in moved) else None,
                               changed.get("Obstacle radius [m]"))
        if self.mode == "plan":
            self.planner.advance(dt * self.config.speed)
        elif self.mode in ("test", "run") and self.follower is not None:
            self.t += dt * self.config.speed
            self.run_frames += 1
            self.run_time += dt
            if self.t >= self.path.duration:
                closed = np.allclose(self.path.points[0], self.path.points[-1])
                if self.mode == "run" and closed:
                    if not self._pose_along(self.path.duration):
                        return
                    self.t -= self.path.duration
                    self.follower.restart(0)
                    self.follower.react()  # the whole loop lies ahead again
                    self._update_motion()
                else:
                    if self._pose_along(self.path.duration):
                        self._update_motion()
                        self.message = ("test run finished" if self.mode == "test" else "run finished") \
                            + self._motion_words()
                        self.mode = "idle"
                    return
            if not self._pose_along(self.t):
                return
        self.frames += 1

    def _status(self, message: str | None = None) -> None:
        if message is not None:
            self.message = message
        setup = (f"Setup: {self.robot_name} | {self.method} | editing {POINT_NAMES[self.edit]} | "
                 f"{len(self.path.points)} points | planner {self.planner.method}, {self.planner.timeout:g} s")
        self.controls.status(setup, f"Status: {self.message}")
        self.write_status()

    def state(self) -> dict:
        """The app's state as a JSON-friendly dict (the status file's content)."""
        f = self.follower
        obstacle = self.scene.obstacles.get("obstacle")
        return {
            "url": self.meshcat.web_url(), "page_url": self.page_url, "robot": self.robot_name, "method": self.method, "mode": self.mode,
            "message": self.message, "editing": POINT_NAMES[self.edit], "points": self.points.tolist(),
            "n_points": len(self.path.points),
            "obstacle": None if obstacle is None else obstacle.position.tolist(),
            "obstacle_radius": None if obstacle is None else float(obstacle.shape.radius),
            "scene_obstacles": [] if self.scene_file is None else self.scene_file.names,
            "solutions": f is not None, "index": None if f is None else int(f.index),
            "plan_hash": None if f is None else hashlib.sha256(f.Q.tobytes() + f.points.tobytes()).hexdigest()[:16],
            "events": self.events, "regenerated_total": self.regenerated_total, "last_event": self.last_event,
            "clicks": dict(self.clicks), "frames": self.frames,
            "run_fps": self.run_frames / self.run_time if self.run_time > 0 else None,
            "elapsed": time.monotonic() - self.started,
            "q": self.view.q.tolist(), **self.planner.state(), **(self.motion if f is not None else {}),
        }

    def write_status(self) -> None:
        """Writes :meth:`state` to ``config.status_file`` atomically (if set)."""
        if not self.config.status_file:
            return
        path = Path(self.config.status_file)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.state(), indent=1))
        os.replace(tmp, path)

    def run(self, max_seconds: float | None = None) -> dict:
        """The loop: runs until ``max_seconds`` (``None``: until Ctrl-C); returns the final state."""
        period = 1.0 / self.config.fps
        deadline = np.inf if max_seconds is None else time.monotonic() + float(max_seconds)
        last = time.monotonic()
        last_write = 0.0
        shown = None
        self._status()
        while time.monotonic() < deadline:
            now = time.monotonic()
            dt, last = now - last, now
            self.tick(min(dt, 0.25))
            key = (self.message, self.method, self.edit, self.robot_name, len(self.path.points))
            if key != shown or now - last_write > 0.5:
                self._status()
                shown, last_write = key, now
            time.sleep(max(0.0, period - (time.monotonic() - now)))
        self._status()
        return self.state()

