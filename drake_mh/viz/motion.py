"""Animating a planned motion (:class:`drake_mh.planning.MotionResult`) with its clearance.

::

    result = drake_mh.planning.solve_motion(problem, "rrt_connect_smooth")
    view = drake_mh.viz.show_motion(problem, result)        # live, in Meshcat
    html = drake_mh.viz.motion_html(problem, result)        # a report's self-contained page
    print(drake_mh.viz.motion_caption(result))              # "rrt_connect_smooth: ... >= 170.6 mm"

Only a verified motion is animated (``result.success``: the whole motion certified
collision-free and its retimed trajectory certified): anything else raises
:class:`~drake_mh.errors.InvalidArgument` naming why the planner's answer was rejected. The
drawing is :func:`drake_mh.viz.show`'s (robot, obstacles, end-effector path, goal pose), plus
the clearance: a ghost of the robot at the animation frame closest to the obstacles, named
after the certified bound (``ghosts/closest_...mm``) and the closest-point segments there.
"""

from __future__ import annotations

import numpy as np

from drake_mh.errors import InvalidArgument

__all__ = ["show_motion", "motion_html", "motion_caption", "motion_samples"]

CLOSEST_COLOUR = (0.95, 0.35, 0.1, 0.35)
"""The ghost at the frame closest to the obstacles (translucent orange-red)."""


def _robot_scene(problem_or_robot, scene):
    """``(robot, scene, goal pose or None)`` of a MotionProblem or of a robot (and ``scene``)."""
    from drake_mh.robot import Robot

    if isinstance(problem_or_robot, Robot):
        return problem_or_robot, scene, None
    robot = getattr(problem_or_robot, "robot", None)
    if not isinstance(robot, Robot):
        raise InvalidArgument("pass the MotionProblem (or the robot and scene=...) the result was planned for, "
                              f"got {type(problem_or_robot).__name__}")
    return robot, scene if scene is not None else problem_or_robot.scene, getattr(problem_or_robot, "goal_pose", None)


def motion_samples(result, fps: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    """``(t (K,), Q (K, nq))``: the verified result's retimed trajectory at ``K = ceil(duration fps) + 1``
    evenly spaced times from its start to its end (the goal), ``t`` from 0.

    Raises:
        InvalidArgument: ``result`` is not a verified motion with a trajectory (the message
            says why the planner's answer was rejected), or ``fps`` is not positive.
    """
    fps = float(fps)
    if not np.isfinite(fps) or fps <= 0:
        raise InvalidArgument(f"fps must be a positive frame rate [Hz], got {fps}")
    if not hasattr(result, "success") or not hasattr(result, "trajectory"):
        raise InvalidArgument(f"result must be a drake_mh.planning.MotionResult, got {type(result).__name__}")
    if not result.success:
        raise InvalidArgument(f"only verified motions are animated: {result.method} was not certified "
                              f"({result.message or 'no path'})")
    traj = result.trajectory
    if traj is None:
        raise InvalidArgument(f"{result.method}'s result has no retimed trajectory: solve_motion(..., retime=True)")
    t0, t1 = float(traj.start_time), float(traj.end_time)
    t = np.linspace(t0, t1, max(2, int(np.ceil((t1 - t0) * fps)) + 1))
    return t - t0, np.asarray(traj.position(t), dtype=float)


def clearance_words(result, scene=None, samples: int = 60) -> str:
    """The motion's clearance in words: its certified bound (over the whole motion, under the
    sphere model, which reads up to its covering tolerance less than the exact geometry) and,
    with ``scene``, beside it the sampled minimum (Drake's exact distance at ``samples``
    configurations along the trajectory), each labelled."""
    words = f"certified clearance >= {result.min_clearance * 1e3:.1f} mm (bound over the whole motion)"
    trajectory = result.trajectory
    if scene is not None and scene.obstacles and trajectory is not None:
        Q = trajectory.position(np.linspace(trajectory.start_time, trajectory.end_time, samples))
        sampled = float(np.min(scene.exact_min_distance(Q)))
        words += f", sampled minimum {sampled * 1e3:.1f} mm (exact distance at {samples} configurations)"
    return words


def motion_caption(result, scene=None) -> str:
    """One line about a motion result: method, planning time, duration, clearance
    (:func:`clearance_words`: the certified bound, and with ``scene`` the sampled minimum
    beside it), or why it failed."""
    if not result.success:
        return f"{result.method}: not certified after {result.planning_time:.2f} s: {result.message or 'no path'}"
    return (f"{result.method}: planned in {result.planning_time * 1e3:.1f} ms, {len(result.path)} waypoints, "
            f"{result.duration:.2f} s motion, {clearance_words(result, scene)}")


def show_motion(problem_or_robot, result, scene=None, *, fps: float = 30.0, loop: bool = True,
                closest: bool = True, meshcat=None, prefix: str = "/drake_mh", frame: bool = True):
    """Animate a verified motion in Meshcat, with its certified clearance.

    Args:
        problem_or_robot: the :class:`drake_mh.planning.MotionProblem` the result answers (its
            robot, scene and goal pose are drawn), or the robot (then pass ``scene``).
        result: the :class:`drake_mh.planning.MotionResult` (``success`` required).
        scene: the obstacles (default the problem's).
        fps: animation frame rate [Hz]; the motion is stretched by less than a frame so that the
            last frame is the goal.
        loop: repeat the animation.
        closest: draw the clearance: a ghost at the frame closest to the obstacles (exact
            distance over the frames), named ``closest_<certified bound>mm``, and the
            closest-point segments there.
        meshcat, prefix, frame: as for :func:`drake_mh.viz.show`.

    Returns:
        The :class:`drake_mh.viz.View`.

    Raises:
        InvalidArgument: the result is not a verified motion, or a bad argument.
    """
    from drake_mh.viz.show import show

    robot, scene, goal_pose = _robot_scene(problem_or_robot, scene)
    t, Q = motion_samples(result, fps)
    robot.check_Q(Q, "the result's trajectory")
    frames = np.arange(t.size) / float(fps)  # one frame per sample, the last at the goal (<= 1 frame slower)
    view = show(robot, (frames, Q), scene, target=goal_pose, fps=fps, loop=loop, meshcat=meshcat, prefix=prefix,
                frame=frame, distances=False)
    if closest and scene is not None and scene.obstacles:
        distances = np.array([scene.min_distance(q) for q in Q])
        k = int(np.argmin(distances))
        view.add_ghost(Q[k], f"closest {result.min_clearance * 1e3:.1f} mm certified", colour=CLOSEST_COLOUR)
        view.add_distances(scene, Q[k], max_distance=max(0.3, float(distances[k]) + 0.05), max_pairs=3)
        view.set_q(Q[0])
    return view


def motion_html(problem_or_robot, result, scene=None, **kwargs) -> str:
    """:func:`show_motion`'s drawing as a self-contained HTML page (for reports), recorded on a
    private Meshcat unless ``meshcat=`` is given (as :func:`drake_mh.viz.animation_html`).

    Raises:
        InvalidArgument: the result is not a verified motion.
    """
    from drake_mh.viz.server import private_meshcat

    if kwargs.get("meshcat") is not None:
        return show_motion(problem_or_robot, result, scene, **kwargs).html()
    motion_samples(result)  # refuse an uncertified result before a server starts
    with private_meshcat() as meshcat:
        view = show_motion(problem_or_robot, result, scene, **{**kwargs, "meshcat": meshcat})
        try:
            return view.html()
        finally:
            del view
