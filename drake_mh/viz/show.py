"""Two-line entry points: :func:`show` a configuration or trajectory, export it as HTML."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.viz.inputs import as_motion
from drake_mh.viz.server import private_meshcat
from drake_mh.viz.view import View

__all__ = ["show", "animation_html", "save_animation"]


def show(robot, q_or_traj=None, scene=None, *, target=None, ghosts=(), distances: bool | None = None,
         ee_path: bool = True, fps: float = 30.0, move_obstacles: bool = True, obstacle_positions=None,
         loop: bool = True, meshcat=None, prefix: str = "/drake_mh", role: str = "illustration",
         frame: bool = True) -> View:
    """Show a robot at a configuration, or play a trajectory, in Meshcat.

    ::

        view = drake_mh.viz.show(robot, ik_result, scene=scene, target=X_WT)
        print(view.url)            # http://localhost:7000

    Args:
        robot: the :class:`drake_mh.robot.Robot`.
        q_or_traj: what to show (see :func:`drake_mh.viz.inputs.as_motion`): ``q (nq,)``, an
            object with ``.q`` (an IK result), ``(t (K,), Q (K, nq))``, an object with ``.t`` and
            ``.Q``, a study record's ``traj_t``/``traj_q`` mapping, or a Drake ``Trajectory``;
            default ``robot.home``.
        scene: a :class:`drake_mh.scene.Scene` whose obstacles are drawn.
        target: a point ``(3,)`` or pose ``(4, 4)`` to mark, or a sequence of points ``(N, 3)``.
        ghosts: configurations ``(N, nq)`` drawn as semi-transparent copies of the robot.
        distances: draw closest-point segments (needs ``scene``); default: for a single
            configuration with a scene, yes; for a trajectory, no.
        ee_path: draw the end-effector path of a trajectory.
        fps: animation frame rate [Hz].
        move_obstacles: animate obstacles that have a velocity (``Obstacle.velocity_W``).
        obstacle_positions: ``{name: (K, 3)}`` obstacle positions at the trajectory's times.
        loop: repeat the animation.
        meshcat: a Meshcat instance; default the shared localhost server.
        prefix: Meshcat path the view draws under (cleared first).
        role: robot geometry drawn: ``"illustration"`` or ``"proximity"``.
        frame: point the camera at the robot, its motion, obstacles and targets
            (:meth:`View.frame`: planar arms from above, others obliquely); ``False`` keeps
            the camera where it is.

    Returns:
        The :class:`View` (``view.url``, ``view.html()``, ``view.add_ghost(q)`` ...).

    Raises:
        InvalidConfiguration, InvalidTrajectory: wrong shapes (q length, ``len(t) != len(Q)``).
        InvalidArgument: ``q_or_traj`` or another argument is of an unknown kind.
        VisualizationError: Meshcat cannot start.
    """
    motion = as_motion(robot, robot.home if q_or_traj is None else q_or_traj, sample_rate=fps)
    if distances and scene is None:
        raise InvalidArgument("distances=True needs the scene: show(robot, q, scene=scene, distances=True)")
    ghosts_Q = None if ghosts is None or len(ghosts) == 0 else robot.check_Q(ghosts, "ghosts")
    view = View(robot, meshcat=meshcat, prefix=prefix, role=role, clear=True, q=motion.q)
    if scene is not None:
        view.add_obstacles(scene)
    if target is not None:
        _add_targets(view, target)
    if ghosts_Q is not None:
        view.add_ghosts(ghosts_Q)
    if motion.is_trajectory:
        view.animate(motion.t, motion.Q, fps=fps, obstacle_positions=obstacle_positions,
                     move_obstacles=move_obstacles, loop=loop, ee_path=ee_path)
    if scene is not None and (distances if distances is not None else not motion.is_trajectory):
        view.add_distances(scene, motion.q)
    if frame:
        Q = motion.Q if motion.is_trajectory else motion.q[None, :]
        if ghosts_Q is not None:
            Q = np.vstack([Q, ghosts_Q])
        view.frame(Q, _points_shown(robot, Q, scene, target, obstacle_positions, motion))
    return view


def _points_shown(robot, Q, scene, target, obstacle_positions, motion) -> np.ndarray:
    """Points ``(K, 3)`` [m] besides the robot that the camera keeps in view."""
    points = [robot.batch.positions(Q)]
    if target is not None:
        arr = np.asarray(target, dtype=float)
        points.append(arr[:3, 3][None, :] if arr.shape == (4, 4) else arr.reshape(-1, 3))
    if scene is not None:
        span = (motion.t[-1] - motion.t[0]) if motion.is_trajectory else 0.0
        for obstacle in scene.obstacles.values():
            p = np.asarray(obstacle.position, dtype=float)
            points.append(np.vstack([p, p + span * np.asarray(obstacle.velocity_W, dtype=float)]))
    for P in dict(obstacle_positions or {}).values():
        points.append(np.asarray(P, dtype=float).reshape(-1, 3))
    return np.vstack(points)


def _add_targets(view: View, target) -> None:
    """A point (3,) or pose (4, 4) is one target; points (N, 3) are N targets."""
    if np.ndim(target) == 2 and np.shape(target)[1] == 3:
        for i, p_WT in enumerate(target):
            view.add_target(p_WT, f"target{i}")
    else:
        view.add_target(target)


def animation_html(robot, q_or_traj, scene=None, **show_kwargs) -> str:
    """Self-contained HTML page (Meshcat ``StaticHtml``) of :func:`show`'s drawing.

    For reports: ``case.attach("motion.html", drake_mh.viz.animation_html(robot, (t, Q)))``.
    Unless ``meshcat=`` is given, the page is recorded on a private Meshcat of its own
    (:func:`drake_mh.viz.server.private_meshcat`: localhost, any free port, never announced,
    closed before this returns), so a batch study neither prints server URLs nor leaves
    servers running, and the shared server a user watches is left alone. The camera is framed
    on the robot and its motion (``frame=True``).

    Args:
        robot, q_or_traj, scene, **show_kwargs: as for :func:`show`.

    Returns:
        The page: about 2.2 MB, plus about 3.7 kB per link and animation second at 30 fps
        (the Panda: about 30 kB per second).
    """
    if show_kwargs.get("meshcat") is not None:
        return show(robot, q_or_traj, scene, **show_kwargs).html()
    with private_meshcat() as meshcat:
        view = show(robot, q_or_traj, scene, **{**show_kwargs, "meshcat": meshcat})
        try:
            return view.html()
        finally:
            del view  # the view holds the server: drop it inside the block so the server closes


def save_animation(path, robot, q_or_traj, scene=None, **show_kwargs) -> Path:
    """Write :func:`animation_html` to ``path`` (folders created) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(animation_html(robot, q_or_traj, scene, **show_kwargs), encoding="utf-8")
    return path
