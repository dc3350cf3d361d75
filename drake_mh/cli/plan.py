"""``drake-mh plan``: plan one point-to-point motion, print the verified result, show it if asked.

Example::

    drake-mh plan --robot panda --goal-q 1.2 -0.3 0 -2.0 0 1.9 0.8 --sphere 0.45 0.1 0.5 0.1
    drake-mh plan --robot panda --position 0.4 0.3 0.4 --box 0.5 0 0.2 0.2 0.6 0.02 --json
    drake-mh plan --set cage --index 2 --method rrt_connect --html motion.html
    drake-mh plan --robot seed000_6dof --goal-q 1.6 0.3 0 0 0 0 --show --max-seconds 30
    drake-mh plan --robot arm.urdf --goal-q ... --limits joint_limits.yaml --out motion.json
    drake-mh plan --robot panda --scene tests/data/scenes/cell.sdf --goal-q -0.35 -1.44 -1.13 -2.97 2.33 1.52 1.89

The problem is a :class:`drake_mh.planning.MotionProblem`: the robot (``--robot`` and its model
options), obstacles (``--scene FILE``, any scene file :meth:`drake_mh.scene.Scene.load` reads,
its ``package://`` names resolved with ``--package``; ``--sphere`` / ``--box``, repeatable), the
start (``--start-q``, default home) and the goal: a configuration (``--goal-q``) or an
end-effector position (``--position``, with ``--rpy`` or else the start's orientation, goal
configurations from collision-free IK);
or one problem of a generated set (``--set NAME --index K``, :mod:`drake_mh.planning.problems`).
:func:`drake_mh.planning.solve_motion` plans and verifies it. ``--html`` writes the animation
with its certified clearance (:func:`drake_mh.viz.motion_html`), ``--show`` plays it in Meshcat
until Ctrl-C (or ``--max-seconds``). ``--out FILE`` writes the retimed trajectory sampled at
``--rate`` (``.json`` / ``.yaml``: ROS 2 ``JointTrajectory`` shape, ``.csv``;
:mod:`drake_mh.trajectories.export`); ``--limits`` reads a MoveIt ``joint_limits.yaml``,
``--velocity-scaling`` / ``--acceleration-scaling`` are MoveIt's factors. Output paths are
checked before planning. The printed result says where every enforced limit came from.

Exit code 0 when the motion is verified, 1 when it is not (no path, not certified), 2 for bad
input (unknown robot, method or set; a start or goal in collision: one line saying why).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

__all__ = ["register", "cmd_plan"]


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``plan``."""
    p = subparsers.add_parser(
        "plan",
        parents=[common],
        help="plan one collision-free motion (any planner; verified, retimed, certified clearance)",
        description="Plan a point-to-point motion with any method of drake_mh.planning.available_motion_methods() "
        "among sphere and box obstacles and those of a scene file (or one problem of a generated set), verified the "
        "same way for every method: the whole motion certified collision-free, retimed and certified. Prints the "
        "result (--json: one object); --html / --show animate it with its certified clearance. Exit code 0: "
        "verified; 1: no verified motion; 2: bad input.",
    )
    p.add_argument("--robot", default="panda", help="bundled robot name or model file (default panda)")
    from drake_mh.cli.options import add_robot_options

    add_robot_options(p)
    goal = p.add_mutually_exclusive_group()
    goal.add_argument("--goal-q", nargs="+", type=float, default=None, metavar="Q", help="goal configuration [rad]")
    goal.add_argument("--position", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"),
                      help="goal position of the end effector [m] (orientation: --rpy, else the start's)")
    goal.add_argument("--set", default=None, metavar="NAME",
                      help="a generated problem set of drake_mh.planning.problems (table_pick, cage, ...) instead")
    p.add_argument("--rpy", nargs=3, type=float, default=None, metavar=("R", "P", "Y"),
                   help="goal roll-pitch-yaw [rad] with --position")
    p.add_argument("--index", type=int, default=0, help="problem of --set (default 0)")
    p.add_argument("--start-q", nargs="+", type=float, default=None, metavar="Q",
                   help="start configuration [rad] (default the robot's home)")
    p.add_argument("--sphere", nargs=4, type=float, action="append", default=[], metavar=("X", "Y", "Z", "R"),
                   help="a spherical obstacle [m] (repeatable)")
    p.add_argument("--box", nargs=6, type=float, action="append", default=[], metavar=("X", "Y", "Z", "LX", "LY", "LZ"),
                   help="an axis-aligned box obstacle: centre and side lengths [m] (repeatable)")
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="obstacles of a scene file: drake_mh scene YAML, SDFormat (.sdf, .world), URDF, model "
                        "directives (.dmd.yaml), MoveIt .scene or planning-scene YAML, cuRobo world YAML "
                        "(docs/scene_files.md); with --sphere / --box")
    p.add_argument("--self-collision", action="store_true", help="check the robot's links against each other too")
    p.add_argument("--clearance", type=float, default=0.0, help="required distance to obstacles [m] (default 0)")
    p.add_argument("--method", default=None, help="planner (default rrt_connect_smooth)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--timeout", type=float, default=10.0,
                   help="limit of the search [s]: a pose goal's IK and the planning together (default 10)")
    p.add_argument("--retime", choices=("auto", "toppra", "ruckig"), default="auto",
                   help="time law: auto (toppra, else ruckig), toppra (fastest; jerk not limited), ruckig "
                        "(jerk-limited, on the straight segments, at rest at each waypoint)")
    from drake_mh.cli.options import add_retime_options

    add_retime_options(p)
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--html", default=None, metavar="PATH", help="write the animation page (opens offline)")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="write the retimed trajectory, sampled at --rate: .json / .yaml (ROS 2 JointTrajectory "
                        "shape: positions, velocities, accelerations, effort, time_from_start) or .csv")
    p.add_argument("--show", action="store_true", help="play it in Meshcat (localhost) until Ctrl-C")
    p.add_argument("--max-seconds", type=float, default=None, metavar="S", help="with --show: stop after S seconds")
    p.set_defaults(func=cmd_plan)


def _problem(args):
    """The MotionProblem the options describe."""
    import numpy as np

    import drake_mh
    from drake_mh.errors import InvalidArgument
    from drake_mh.planning import MotionProblem

    if args.set is not None:
        from drake_mh.planning.problems import problem_set

        if args.scene is not None:
            raise InvalidArgument("--scene does not combine with --set: a generated problem brings its own scene")
        if args.index < 0:
            raise InvalidArgument(f"--index must be >= 0, got {args.index}")
        robot = args.robot
        if args.limits is not None:
            from drake_mh.planning.problems import load_problem_robot
            from drake_mh.robot.limits import apply_limits

            robot = load_problem_robot(args.robot)
            apply_limits(robot, args.limits)
        return problem_set(args.set, robot, count=1, first=args.index, clearance=args.clearance)[0]
    if args.goal_q is None and args.position is None:
        raise InvalidArgument("give the goal: --goal-q Q1 ... Qn, --position X Y Z [--rpy R P Y], or --set NAME")
    if args.rpy is not None and args.position is None:
        raise InvalidArgument("--rpy needs --position")
    from drake_mh.cli.options import load_robot_from_args

    robot = load_robot_from_args(args)
    scene = drake_mh.Scene(robot, self_collision=args.self_collision)
    if args.scene is not None:
        from drake_mh.robot.packages import parse_package_option

        scene.load(args.scene, packages=parse_package_option(args.package) or None)
    for i, (x, y, z, r) in enumerate(args.sphere):
        scene.add(f"sphere{i}", drake_mh.Sphere(r), [x, y, z])
    for i, (x, y, z, lx, ly, lz) in enumerate(args.box):
        scene.add(f"box{i}", drake_mh.Box((lx, ly, lz)), [x, y, z])
    start = robot.home if args.start_q is None else np.asarray(args.start_q, dtype=float)
    if args.position is not None:
        goal = np.array(robot.fk(robot.check_q(start, "--start-q")), dtype=float)
        if args.rpy is not None:
            from pydrake.math import RollPitchYaw

            goal[:3, :3] = RollPitchYaw(*args.rpy).ToRotationMatrix().matrix()
        goal[:3, 3] = args.position
    else:
        goal = np.asarray(args.goal_q, dtype=float)
    return MotionProblem(robot, scene, start, goal, clearance=args.clearance, name="drake-mh plan")


def cmd_plan(args: argparse.Namespace) -> int:
    """``drake-mh plan``: returns 0 on a verified motion, 1 otherwise."""
    from drake_mh.errors import InvalidArgument, UnknownMethod
    from drake_mh.planning import available_motion_methods, solve_motion
    from drake_mh.viz.app_plan import default_plan_method

    method = args.method or default_plan_method()
    if method not in available_motion_methods():  # before loading anything: fail fast
        raise UnknownMethod(method, list(available_motion_methods()), what="motion planning method")
    if not args.timeout > 0:
        raise InvalidArgument(f"--timeout must be > 0 s, got {args.timeout}")
    if args.max_seconds is not None and not args.max_seconds > 0:
        raise InvalidArgument(f"--max-seconds must be > 0, got {args.max_seconds}")
    from drake_mh.cli.options import check_output_path
    from drake_mh.planning.verify import check_scaling
    from drake_mh.trajectories.export import FORMATS, sample_times

    html = None if args.html is None else check_output_path(args.html, "--html")  # before planning
    out = None if args.out is None else check_output_path(args.out, "--out", FORMATS)
    sample_times(1.0, args.rate)  # the rate's check
    check_scaling(args.velocity_scaling, args.acceleration_scaling)
    problem = _problem(args)
    result = solve_motion(problem, method, seed=args.seed, timeout=args.timeout,
                          retime=True if args.retime == "auto" else args.retime,
                          velocity_scaling=args.velocity_scaling, acceleration_scaling=args.acceleration_scaling)
    note = sys.stderr if args.json else sys.stdout
    samples = None
    if result.success and out is not None:
        samples = result.trajectory.save(out, problem.robot, args.rate)
    _print(problem, result, args.json, out if samples is not None else None)
    if samples is not None:
        print(f"trajectory written to {out} ({len(samples)} samples at {args.rate:g} Hz)", file=note)
    if result.success and html is not None:
        from drake_mh.viz import motion_html

        html.parent.mkdir(parents=True, exist_ok=True)
        html.write_text(motion_html(problem, result), encoding="utf-8")
        print(f"animation written to {html}", file=note)
    if result.success and args.show:
        _show(problem, result, args.max_seconds, sys.stderr if args.json else sys.stdout)
    return 0 if result.success else 1


def _print(problem, result, as_json: bool, out=None) -> None:
    import numpy as np

    from drake_mh.viz import motion_caption

    robot = problem.robot
    if as_json:
        data = {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in result.record().items()}
        data.update(robot=robot.name, joint_names=list(robot.joint_names), q_start=problem.q_start.tolist(),
                    path=None if result.path is None else np.asarray(result.path).tolist(),
                    goal_time=result.goal_time, seed=result.seed, obstacles=list(problem.scene.obstacles),
                    caption=motion_caption(result, problem.scene),
                    limits=None if result.limits is None else result.limits.as_dict(),
                    trajectory_file=None if out is None else str(out))
        print(json.dumps(data))
        return
    state = "verified" if result.success else "FAILED"
    print(f"{state}: {motion_caption(result, problem.scene)} ({robot.name}, {len(problem.scene.obstacles)} obstacles)")
    if result.success:
        jerk = ("jerk not limited (toppra's acceleration steps; --retime ruckig limits it)"
                if result.jerk_limited is False else f"max jerk {result.max_jerk:.3g} rad/s^3")
        print(f"  path {result.path_length:.3f} rad, {jerk}, goal IK "
              f"{result.goal_time:.2f} s, verification {result.verify_time * 1e3:.1f} ms")
        print(f"  goal q = [{', '.join(f'{v:.4f}' for v in result.path[-1])}]")
        if result.limits is not None:
            print("  limits enforced (value per joint | where it came from):")
            for line in result.limits.summary():
                print(f"    {line}")


def _show(problem, result, max_seconds, out) -> None:
    import logging

    import pydrake.geometry  # noqa: F401 - pydrake ties the "drake" logger to Drake's on import

    from drake_mh.viz import get_meshcat, show_motion

    drake_log = logging.getLogger("drake")  # one line with the URL: ours
    level = drake_log.level
    drake_log.setLevel(max(logging.WARNING, drake_log.getEffectiveLevel()))
    try:
        meshcat = get_meshcat(announce=False)
    finally:
        drake_log.setLevel(level)
    view = show_motion(problem, result, meshcat=meshcat)
    print(f"showing the motion at {view.url} (localhost; Ctrl-C to stop)", file=out, flush=True)
    deadline = time.monotonic() + (max_seconds if max_seconds is not None else float("inf"))
    try:
        while time.monotonic() < deadline:
            time.sleep(min(0.2, max(0.0, deadline - time.monotonic())))
    except KeyboardInterrupt:
        pass
