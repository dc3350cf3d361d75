"""A :class:`View`: one robot and what goes with it (obstacles, paths, targets, ghosts,
closest-point lines, animations) drawn in Meshcat under one path prefix.

Scene tree under the prefix (default ``/drake_mh``)::

    robot/<link>/<geometry>       the robot (links posed by set_q / the animation)
    ghosts/<name>/<link>/...      semi-transparent copies at other configurations
    obstacles/<name>              obstacles of a Scene (posed X_WO, moved by animations)
    paths/<name>                  polylines (e.g. the end-effector path)
    targets/<name>[/triad]        small spheres, with an x/y/z triad for poses
    distances/{clear,close}       closest-point segments from Scene.distances

Everything is drawn directly from the robot's SceneGraph (see :mod:`drake_mh.viz.geometry`);
no second diagram is built. :meth:`View.html` returns the self-contained page
(``Meshcat.StaticHtml()``) of the whole Meshcat scene, animation included.
"""

from __future__ import annotations

import functools
import logging
from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument, UnknownObstacle
from drake_mh.viz.geometry import RobotGeometry, path_name, rgba
from drake_mh.viz.inputs import as_point, as_pose, check_trajectory, resample
from drake_mh.viz.server import check_thread, get_meshcat

logger = logging.getLogger(__name__)

__all__ = ["View", "COLOURS"]

COLOURS = {
    "ghost": (0.3, 0.55, 1.0, 0.3),
    "obstacle": (0.9, 0.08, 0.08, 0.45),  # translucent red: apart from orange/yellow arms, white Panda
    "path": (0.1, 0.35, 0.9, 1.0),
    "target": (0.1, 0.75, 0.2, 0.9),
    "clear": (0.2, 0.6, 0.2, 1.0),
    "close": (0.9, 0.1, 0.1, 1.0),
}
"""Default colours ``(r, g, b, a)`` of the drawn elements."""


def _transform(X, what: str):
    from pydrake.math import RigidTransform, RotationMatrix

    X = as_pose(X, what)
    R = X[:3, :3]
    if not (np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0
            and np.allclose(X[3], [0, 0, 0, 1])):
        raise InvalidArgument(f"{what}: not a rigid transform (the rotation part must be orthonormal "
                              "with determinant +1 and the last row [0, 0, 0, 1]); orthonormalize it, "
                              "e.g. with pydrake.math.RotationMatrix.ProjectToRotationMatrix")
    return RigidTransform(RotationMatrix(R), X[:3, 3])


def _same_thread(method):
    """Drawing methods check the calling thread first: Drake's Meshcat aborts the process
    (SIGABRT) when called from another thread than the one that made it."""
    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        check_thread(self.meshcat)
        return method(self, *args, **kwargs)

    return wrapper


class View:
    """A robot drawn in Meshcat, with helpers for everything around it.

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        meshcat: a ``pydrake.geometry.Meshcat``; default this thread's shared server
            (:func:`drake_mh.viz.get_meshcat`, localhost only).
        prefix: Meshcat path under which this view draws (must start with ``/``).
        role: robot geometry to draw, ``"illustration"`` (visual) or ``"proximity"``.
        clear: delete whatever is under ``prefix`` first (and the current recording).
        q: initial configuration ``(nq,)``; default ``robot.home``.

    Attributes:
        robot, meshcat, prefix, q: as given (``q`` is the last configuration shown).
    """

    def __init__(self, robot, meshcat=None, prefix: str = "/drake_mh", role: str = "illustration",
                 clear: bool = True, q=None):
        if not isinstance(prefix, str) or not prefix.startswith("/") or prefix.rstrip("/") == "":
            raise InvalidArgument(f"prefix must be a Meshcat path like '/drake_mh', got {prefix!r}")
        q0 = robot.check_q(robot.home if q is None else q)  # before anything is drawn or cleared
        self.robot = robot
        self.meshcat = meshcat if meshcat is not None else get_meshcat()
        check_thread(self.meshcat)
        self.prefix = prefix.rstrip("/")
        self.geometry = RobotGeometry(robot, role)
        self._ghosts: dict[str, str] = {}
        self._scene = None
        self._scene_names: set[str] = set()
        if clear:
            self.clear()
        self.geometry.draw(self.meshcat, self.robot_path)
        self.q = None
        self.set_q(q0)

    # --- paths and basics -------------------------------------------------------------------

    @property
    def robot_path(self) -> str:
        """Meshcat path of the robot, ``<prefix>/robot``."""
        return f"{self.prefix}/robot"

    @property
    def url(self) -> str:
        """URL of the Meshcat server (``http://localhost:PORT``)."""
        return self.meshcat.web_url()

    def link_paths(self, ghost: str | None = None) -> dict[str, str]:
        """``{link: Meshcat path}`` of the robot (or of a ghost)."""
        root = self.robot_path if ghost is None else self._ghost_path(ghost)
        return self.geometry.link_paths(root)

    def clear(self) -> None:
        """Delete everything under the prefix, and the animation (Meshcat has one per server)."""
        check_thread(self.meshcat)
        self.meshcat.Delete(self.prefix)
        self.meshcat.DeleteRecording()
        self.meshcat.PublishRecording()  # an empty animation replaces the published one
        self._ghosts.clear()
        self._scene_names = set()

    @_same_thread
    def set_q(self, q) -> View:
        """Pose the robot at ``q (nq,)``; returns the view (calls chain)."""
        q = self.robot.check_q(q)
        self.geometry.set_configuration(self.meshcat, self.robot_path, q)
        self.q = q
        return self

    def __repr__(self) -> str:
        return f"View({self.robot.name!r}, url={self.url!r}, prefix={self.prefix!r})"

    def _repr_html_(self) -> str:  # notebooks: a link instead of an embedded 2 MB page
        return f'<a href="{self.url}" target="_blank">Meshcat: {self.robot.name} at {self.url}</a>'

    # --- ghosts --------------------------------------------------------------------------

    def _ghost_path(self, name: str) -> str:
        if name not in self._ghosts:
            raise InvalidArgument(f"no ghost named {name!r}; ghosts: {sorted(self._ghosts) or '(none)'}")
        return self._ghosts[name]

    @_same_thread
    def add_ghost(self, q, name: str | None = None, colour=COLOURS["ghost"], opacity: float | None = None) -> str:
        """Draw a semi-transparent copy of the robot at ``q (nq,)``.

        Args:
            q: the configuration.
            name: ghost name (default ``ghost<i>``); an existing name is redrawn.
            colour: ``(r, g, b[, a])``; its alpha is the opacity unless ``opacity`` is given.
            opacity: alpha in [0, 1] overriding the colour's.

        Returns:
            The ghost's name.
        """
        q = self.robot.check_q(q)
        name = name if name is not None else f"ghost{len(self._ghosts)}"
        if opacity is not None and not 0 <= float(opacity) <= 1:
            raise InvalidArgument(f"opacity must be in [0, 1], got {opacity}")
        path = f"{self.prefix}/ghosts/{path_name(name)}"
        self.geometry.draw(self.meshcat, path, colour=colour, opacity=opacity)
        self.geometry.set_configuration(self.meshcat, path, q)
        self._ghosts[name] = path
        return name

    @_same_thread
    def add_ghosts(self, Q, colour=COLOURS["ghost"], name: str = "ghost") -> list[str]:
        """One ghost per row of ``Q (N, nq)``, named ``<name>0``, ``<name>1`` ..."""
        Q = self.robot.check_Q(Q, "Q")
        return [self.add_ghost(q, f"{name}{i}", colour) for i, q in enumerate(Q)]

    # --- obstacles -----------------------------------------------------------------------

    @_same_thread
    def add_obstacles(self, scene, colour=COLOURS["obstacle"]) -> list[str]:
        """Draw every obstacle of a :class:`drake_mh.scene.Scene` at its pose.

        Returns:
            The obstacle names; their paths are ``<prefix>/obstacles/<name>``.
        """
        c = rgba(colour, "colour")
        self.meshcat.Delete(f"{self.prefix}/obstacles")
        for name, obstacle in scene.obstacles.items():
            path = self.obstacle_path(name)
            self._draw_shape(path, obstacle.shape, c)
            self.meshcat.SetTransform(path, _transform(obstacle.X_WO, f"obstacle {name!r} pose"))
        self._scene, self._scene_names = scene, set(scene.obstacles)
        return list(scene.obstacles)

    @_same_thread
    def update_obstacles(self, scene=None, colour=COLOURS["obstacle"]) -> None:
        """Move the drawn obstacles to the scene's current poses (live views: cheap, no redraw).

        Obstacles added to the scene since are drawn, removed ones deleted.

        Args:
            scene: the scene; default the one last given to :meth:`add_obstacles`.
        """
        scene = scene if scene is not None else self._scene
        if scene is None:
            raise InvalidArgument("no scene drawn yet: call add_obstacles(scene) first or pass the scene")
        drawn = self._scene_names
        current = scene.obstacles
        for name in set(drawn) - set(current):
            self.meshcat.Delete(self.obstacle_path(name))
        for name, obstacle in current.items():
            if name not in drawn:
                self._draw_shape(self.obstacle_path(name), obstacle.shape, rgba(colour, "colour"))
            self.meshcat.SetTransform(self.obstacle_path(name), _transform(obstacle.X_WO, f"obstacle {name!r} pose"))
        self._scene, self._scene_names = scene, set(current)

    def _draw_shape(self, path: str, shape, colour) -> None:
        """An obstacle's shape at ``path``: a primitive or a mesh (its surface, not its convex
        pieces) as Drake's shape, a point cloud as Meshcat points of its balls' diameter."""
        from drake_mh.geometry.cloud import PointCloud

        if isinstance(shape, PointCloud):
            from pydrake.perception import BaseField, PointCloud as DrakeCloud

            cloud = DrakeCloud(len(shape.points), BaseField.kXYZs)
            cloud.mutable_xyzs()[:] = shape.points.T
            self.meshcat.SetObject(path, cloud, point_size=max(2.0 * shape.radius, 0.002), rgba=colour)
        else:
            self.meshcat.SetObject(path, shape.to_drake(), colour)

    def obstacle_path(self, name: str) -> str:
        """Meshcat path of an obstacle."""
        return f"{self.prefix}/obstacles/{path_name(name)}"

    # --- paths, targets, distances ------------------------------------------------------------

    @_same_thread
    def add_path(self, P_W, name: str = "path", colour=COLOURS["path"], line_width: float = 3.0) -> str:
        """Draw a polyline through the points ``P_W (N, 3)`` [m] (N >= 2).

        Returns:
            Its Meshcat path, ``<prefix>/paths/<name>``.
        """
        P = np.asarray(P_W, dtype=float) if _numeric(P_W) else None
        if P is None or P.ndim != 2 or P.shape[1] != 3 or P.shape[0] < 2 or not np.all(np.isfinite(P)):
            got = getattr(P, "shape", type(P_W).__name__)
            raise InvalidArgument(f"a path needs finite points P_W of shape (N >= 2, 3) [m], got {got}")
        path = f"{self.prefix}/paths/{path_name(name)}"
        self.meshcat.SetLine(path, np.asfortranarray(P.T), float(line_width), rgba(colour, "colour"))
        return path

    @_same_thread
    def add_ee_path(self, Q, name: str = "ee_path", frame: str | None = None, **kwargs) -> str:
        """Draw the path of the end effector (or ``frame``) through the configurations ``Q (N, nq)``."""
        P = self.robot.batch.positions(self.robot.check_Q(Q, "Q"), frame)
        if P.shape[0] == 1:
            P = np.vstack([P, P])
        return self.add_path(P, name, **kwargs)

    @_same_thread
    def add_target(self, X_WT, name: str = "target", radius: float = 0.02, colour=COLOURS["target"],
                   triad_length: float = 0.08) -> str:
        """Draw a target: a sphere at a point ``p_WT (3,)``, plus an x/y/z triad for a pose ``X_WT (4, 4)``.

        Returns:
            Its Meshcat path, ``<prefix>/targets/<name>``.
        """
        from pydrake.geometry import Sphere

        if not np.isfinite(float(radius)) or float(radius) <= 0:
            raise InvalidArgument(f"radius must be a positive length [m], got {radius}")
        arr = np.asarray(X_WT, dtype=float) if _numeric(X_WT) else None
        is_pose = arr is not None and arr.shape == (4, 4)
        X = _transform(X_WT if is_pose else as_point(X_WT, "target"), "target")
        path = f"{self.prefix}/targets/{path_name(name)}"
        self.meshcat.Delete(path)
        self.meshcat.SetObject(f"{path}/sphere", Sphere(float(radius)), rgba(colour, "colour"))
        self.meshcat.SetTransform(path, X)
        if is_pose:
            _draw_triad(self.meshcat, f"{path}/triad", float(triad_length), float(radius) / 4)
        return path

    @_same_thread
    def add_distances(self, scene, q=None, max_distance: float = 0.3, margin: float = 0.02,
                      max_pairs: int | None = 10) -> list:
        """Draw closest-point segments from :meth:`drake_mh.scene.Scene.distances`.

        Pairs closer than ``margin`` [m] are drawn red (``close``), the others green
        (``clear``), with a small sphere on the robot's closest point.

        Args:
            scene: the scene.
            q: configuration; default the robot's current one.
            max_distance: only pairs within this distance [m].
            margin: distance [m] under which a pair is drawn as close.
            max_pairs: draw only the closest ``max_pairs`` pairs (``None``: all).

        Returns:
            The drawn :class:`drake_mh.scene.DistancePair` list (closest first).
        """
        from pydrake.geometry import Sphere
        from pydrake.math import RigidTransform

        q = self.q if q is None else self.robot.check_q(q)
        pairs = scene.distances(q, max_distance=float(max_distance))
        if max_pairs is not None:
            pairs = pairs[: int(max_pairs)]
        root = f"{self.prefix}/distances"
        self.meshcat.Delete(root)
        for group, members in (("close", [p for p in pairs if p.distance < margin]),
                               ("clear", [p for p in pairs if p.distance >= margin])):
            if not members:
                continue
            start = np.asfortranarray(np.array([p.p_W_link for p in members]).T)
            end = np.asfortranarray(np.array([p.p_W_other for p in members]).T)
            colour = rgba(COLOURS[group])
            self.meshcat.SetLineSegments(f"{root}/{group}/segments", start, end, 2.0, colour)
            for i, p in enumerate(members):
                self.meshcat.SetObject(f"{root}/{group}/points/{i}", Sphere(0.006), colour)
                self.meshcat.SetTransform(f"{root}/{group}/points/{i}", RigidTransform(p.p_W_link))
        return pairs

    # --- animations ------------------------------------------------------------------------

    def animate(self, t, Q, fps: float = 30.0, obstacle_positions=None, move_obstacles: bool = False,
                loop: bool = True, ee_path: bool = True) -> int:
        """Record a joint trajectory as a Meshcat animation and publish it.

        The trajectory is sampled at ``fps`` (joint-wise linear between the given samples) so
        every animation frame is exact forward kinematics. A previous recording is replaced.

        Args:
            t: times ``(K,)`` [s], strictly increasing.
            Q: configurations ``(K, nq)``.
            fps: animation frames per second [Hz].
            obstacle_positions: ``{name: P_W (K, 3)}`` positions [m] of obstacles drawn with
                :meth:`add_obstacles` at the times ``t`` (e.g. a follower's obstacle log).
            move_obstacles: move every obstacle of the drawn scene with its constant velocity
                ``velocity_W`` from its current pose (ignored for names in ``obstacle_positions``).
            loop: repeat the animation (else play once and stop on the last frame).
            ee_path: also draw the end-effector path (static polyline).

        Returns:
            The number of animation frames.

        Raises:
            InvalidTrajectory, InvalidConfiguration: inconsistent ``t``/``Q``.
            UnknownObstacle: a name of ``obstacle_positions`` was not drawn.
        """
        t, Q = check_trajectory(self.robot, t, Q)
        fps = float(fps)
        if not np.isfinite(fps) or fps <= 0:
            raise InvalidArgument(f"fps must be a positive frame rate [Hz], got {fps}")
        moving = self._obstacle_tracks(t, obstacle_positions, move_obstacles)
        times, Q_frames = resample(t, Q, fps)
        if ee_path:
            self.add_ee_path(Q_frames)
        meshcat = self.meshcat
        check_thread(meshcat)
        meshcat.DeleteRecording()
        meshcat.StartRecording(fps, False)
        try:
            for time, q in zip(times, Q_frames):
                self.geometry.set_configuration(meshcat, self.robot_path, q, float(time))
            for name, (X_WO, P) in moving.items():
                P_frames = np.column_stack([np.interp(times + t[0], t, P[:, j]) for j in range(3)])
                for time, p in zip(times, P_frames):
                    X = X_WO.copy()
                    X[:3, 3] = p
                    meshcat.SetTransform(self.obstacle_path(name), _transform(X, name), float(time))
        finally:
            meshcat.StopRecording()
        animation = meshcat.get_mutable_recording()
        animation.set_autoplay(True)
        if loop:
            animation.set_loop_mode(animation.LoopMode.kLoopRepeat)
            animation.set_repetitions(1_000_000)
        else:
            animation.set_loop_mode(animation.LoopMode.kLoopOnce)
            animation.set_clamp_when_finished(True)
        meshcat.PublishRecording()
        self.set_q(Q[0])
        return int(times.size)

    def _obstacle_tracks(self, t, obstacle_positions, move_obstacles) -> dict:
        """``{name: (X_WO (4, 4), P_W (K, 3))}`` of the obstacles to animate."""
        drawn = {} if self._scene is None else self._scene.obstacles
        tracks = {}
        for name, P in dict(obstacle_positions or {}).items():
            if name not in drawn:
                raise UnknownObstacle(name, drawn)
            P = np.asarray(P, dtype=float) if _numeric(P) else None
            if P is None or P.shape != (t.size, 3) or not np.all(np.isfinite(P)):
                from drake_mh.errors import InvalidTrajectory

                raise InvalidTrajectory(
                    f"obstacle_positions[{name!r}] must be finite positions of shape ({t.size}, 3) "
                    f"(one per time), got {getattr(P, 'shape', None)}", name, (t.size, 3),
                    getattr(P, "shape", None))
            tracks[name] = (drawn[name].X_WO, P)
        if move_obstacles:
            for name, obstacle in drawn.items():
                if name not in tracks and np.any(obstacle.velocity_W != 0):
                    P = obstacle.position + np.outer(t - t[0], obstacle.velocity_W)
                    tracks[name] = (obstacle.X_WO, P)
        return tracks

    # --- camera -----------------------------------------------------------------------------

    def frame(self, Q=None, extra_points=None, aspect: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
        """Point the camera at the robot over ``Q`` and at ``extra_points`` (see
        :mod:`drake_mh.viz.camera`): planar arms from above along their joint axis, other
        robots obliquely; everything fits the view. Saved pages (:meth:`html`) keep it.

        Args:
            Q: configurations ``(N, nq)`` the robot takes (default the current one).
            extra_points: further points ``(M, 3)`` [m] to keep in view (paths, obstacles, targets).
            aspect: width / height of the viewer the page is shown in (reports: about 2).

        Returns:
            ``(p_WCamera (3,), p_WTarget (3,))`` [m].
        """
        from drake_mh.viz.camera import camera_pose, frame_points, joint_axis_normal, set_camera

        Q = self.q[None, :] if Q is None else self.robot.check_Q(Q, "Q")
        points = frame_points(self.geometry, Q, extra_points)
        p_WC, p_WT = camera_pose(points, joint_axis_normal(self.robot, Q[0]), aspect=aspect)
        check_thread(self.meshcat)
        set_camera(self.meshcat, p_WC, p_WT)
        return p_WC, p_WT

    # --- export -----------------------------------------------------------------------------

    def html(self) -> str:
        """The whole Meshcat scene (and the published animation) as one self-contained HTML page.

        The page embeds the Meshcat viewer's JavaScript and the scene as ``data:`` URLs: it
        opens offline, from a file or inside a report (about 2.2 MB plus the animation).
        """
        check_thread(self.meshcat)
        return self.meshcat.StaticHtml()

    def save_html(self, path) -> Path:
        """Write :meth:`html` to ``path`` (folders created); returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.html(), encoding="utf-8")
        return path


def _numeric(value) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


def _draw_triad(meshcat, path: str, length: float, radius: float) -> None:
    """x (red), y (green), z (blue) axes as thin cylinders of ``length`` [m] under ``path``."""
    from pydrake.geometry import Cylinder, Rgba
    from pydrake.math import RigidTransform, RollPitchYaw

    axes = {
        "x": (RollPitchYaw(0, np.pi / 2, 0), [length / 2, 0, 0], Rgba(1, 0, 0, 1)),
        "y": (RollPitchYaw(-np.pi / 2, 0, 0), [0, length / 2, 0], Rgba(0, 1, 0, 1)),
        "z": (RollPitchYaw(0, 0, 0), [0, 0, length / 2], Rgba(0, 0, 1, 1)),
    }
    for axis, (rpy, p, colour) in axes.items():
        meshcat.SetObject(f"{path}/{axis}", Cylinder(radius, length), colour)
        meshcat.SetTransform(f"{path}/{axis}", RigidTransform(rpy, p))
