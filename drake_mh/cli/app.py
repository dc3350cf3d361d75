"""``drake-mh app``: the interactive planner (framework paper §4, Table 1) in the browser.

Example::

    drake-mh app                                   # seed000_6dof, e3gsa, Table 3 path, obstacle
    drake-mh app --method pso --n-points 80 --generate --run
    drake-mh app --max-seconds 60 --status-file app.json    # headless / scripted use
    drake-mh app --robot panda --goal 0.5 0.3 0.4 --plan pose --plan-method rrt_connect
    drake-mh app --robot panda --scene cell.sdf --no-obstacle   # a cell from a file

Prints the URL of the app's page (``open http://localhost:PORT in a browser``: its controls
beside Meshcat's 3-D view; localhost only) and runs until Ctrl-C or ``--max-seconds``. Exit code
0 on a normal end, 2 for bad input (unknown robot or method, a negative seed: one line naming
what is valid).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from drake_mh.viz.app import AppConfig

__all__ = ["register", "cmd_app", "run_app"]


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``app``."""
    p = subparsers.add_parser(
        "app",
        parents=[common],
        help="interactive planner in the browser (Meshcat): path, IK, run, move the obstacle live",
        description="The framework paper's GUI (Table 1) in the browser: choose robot and algorithm (buttons "
        "cycle them), edit start / via / end points and the number of points (sliders), show the "
        "environment, generate solutions, test run, run / stop, and move the obstacle with its X / Y / Z "
        "sliders while the arm runs: colliding solutions are regenerated (§3.4.1) and the path re-planned "
        "where the obstacle cuts it (§3.4.2). It prints the URL to open: 'open http://localhost:PORT in a "
        "browser' (the app's page: its controls beside Meshcat's 3-D view). Both servers, the page's and "
        "Meshcat's, listen on localhost only.",
    )
    p.add_argument("--robot", action="append", default=None, metavar="NAME",
                   help="robot(s) (bundled names or model files) the 'Next robot' button cycles through; "
                        "the first is loaded "
                        "(default seed000_6dof, panda)")
    from drake_mh.cli.options import add_robot_options

    add_robot_options(p)
    p.add_argument("--method", default="e3gsa", help="IK / planner algorithm (default e3gsa, the paper's)")
    p.add_argument("--start", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"), help="start point [m]")
    p.add_argument("--via", nargs=3, type=float, action="append", default=None, metavar=("X", "Y", "Z"),
                   help="intermediate point [m]; give it twice (default Table 3)")
    p.add_argument("--end", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"), help="end point [m]")
    p.add_argument("--n-points", type=int, default=50, help="points in the path (default 50, Table 3)")
    p.add_argument("--obstacle", nargs=3, type=float, default=(0.2, 0.2, 0.6), metavar=("X", "Y", "Z"),
                   help="obstacle position [m] (default 0.2 0.2 0.6, the paper's)")
    p.add_argument("--obstacle-radius", type=float, default=0.2, help="sphere radius [m] (default 0.2)")
    p.add_argument("--no-obstacle", action="store_true", help="no obstacle")
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="fixed obstacles from a scene file beside the movable one: drake_mh scene YAML, SDFormat, "
                        "URDF, model directives, MoveIt .scene or planning-scene YAML, cuRobo world YAML "
                        "(docs/scene_files.md)")
    p.add_argument("--seed", type=int, default=0, help="seed of generation and regeneration, an integer >= 0 "
                                                        "(default 0)")
    p.add_argument("--budget", type=int, default=None, help="per IK solve, >= 1 (default: the method's)")
    p.add_argument("--fps", type=float, default=30.0, help="frame rate of the loop [Hz] (default 30)")
    p.add_argument("--speed", type=float, default=1.0, help="playback speed (default 1: the path's timing)")
    p.add_argument("--port", type=int, default=None,
                   help="Meshcat's port (default: the first free one from 7000; 0: any free one); the app's "
                        "page, whose URL the app prints, takes the first free port after Meshcat's (0: any free "
                        "one)")
    p.add_argument("--generate", action="store_true", help="generate solutions at start")
    p.add_argument("--run", action="store_true", help="start running at once (implies --generate)")
    p.add_argument("--max-seconds", type=float, default=None, metavar="S",
                   help="stop the app S seconds (wall clock) after it prints its URL, solution generation at "
                        "start included, and exit 0 (for scripts and tests; default: run until Ctrl-C)")
    p.add_argument("--status-file", default=None, metavar="PATH",
                   help="write the app's state as JSON on every change (for scripts and tests)")
    g = p.add_argument_group("point-to-point planning (section 8 of the page)")
    g.add_argument("--plan", choices=("pose", "joints"), default=None,
                   help="plan at start from the robot's home to the goal point (pose, keeping the tool's "
                        "orientation) or to the goal configuration (joints: the home one until its sliders move), "
                        "then play the certified motion")
    g.add_argument("--plan-method", default=None, metavar="NAME",
                   help="motion planner of the Plan buttons (default rrt_connect_smooth; any of "
                        "drake_mh.planning.available_motion_methods(); 'Next planner' cycles them)")
    g.add_argument("--plan-timeout", type=float, default=5.0, metavar="S",
                   help="limit of each search [s]: the goal IK and the planning (default 5)")
    g.add_argument("--goal", nargs=3, type=float, default=None, metavar=("X", "Y", "Z"),
                   help="goal point of the end effector [m] (default: via point 1)")
    g.add_argument("--goal-q", nargs="+", type=float, default=None, metavar="Q",
                   help="goal configuration of the first robot [rad] (default: its home)")
    g.add_argument("--plan-clearance", type=float, default=0.0, metavar="M",
                   help="clearance to the obstacle required along planned motions [m] (default 0)")
    p.set_defaults(func=cmd_app)


def cmd_app(args: argparse.Namespace) -> int:
    """``drake-mh app``: returns 0 when the app ends (``--max-seconds`` or Ctrl-C: "app stopped")."""
    from drake_mh.cli.options import register_robot_options
    from drake_mh.errors import InvalidArgument
    from drake_mh.robot.packages import parse_package_option
    from drake_mh.viz.app import AppConfig

    robots = tuple(args.robot) if args.robot else AppConfig.robots
    register_robot_options(robots, args)  # model paths get --ee-frame / --package
    defaults = AppConfig.points
    via = args.via or [defaults[1], defaults[2]]
    if len(via) != 2:
        raise InvalidArgument(f"give --via exactly twice (intermediate points 1 and 2), got {len(via)}")
    points = (tuple(args.start or defaults[0]), tuple(via[0]), tuple(via[1]), tuple(args.end or defaults[3]))
    if args.max_seconds is not None and not args.max_seconds > 0:
        raise InvalidArgument(f"--max-seconds must be > 0, got {args.max_seconds}")
    if args.status_file is not None:
        _check_writable(args.status_file)
    config = AppConfig(robots=robots, method=args.method, points=points, n_points=args.n_points,
                       obstacle=None if args.no_obstacle else tuple(args.obstacle),
                       obstacle_radius=args.obstacle_radius, seed=args.seed, budget=args.budget, fps=args.fps,
                       speed=args.speed, port=args.port, status_file=args.status_file,
                       plan_method=args.plan_method, plan_timeout=args.plan_timeout,
                       goal=None if args.goal is None else tuple(args.goal),
                       goal_q=None if args.goal_q is None else tuple(args.goal_q), plan_clearance=args.plan_clearance,
                       scene=args.scene, scene_packages=parse_package_option(args.package) or None)
    return run_app(config, generate=args.generate, run=args.run, plan=args.plan, max_seconds=args.max_seconds)


def _check_writable(path: str) -> None:
    """``--status-file`` must be writable before the app starts (not an internal error later)."""
    import os
    from pathlib import Path

    from drake_mh.errors import InvalidArgument

    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.is_dir() or not folder.is_dir() or not os.access(folder, os.W_OK):
        raise InvalidArgument(f"--status-file {path}: cannot write there (its folder must exist and be "
                              "writable, and it must not be a folder)")


def run_app(config: AppConfig, *, generate: bool = False, run: bool = False, plan: str | None = None,
            max_seconds: float | None = None, out=None) -> int:
    """``drake-mh app``: starts the app, prints its URL, runs until Ctrl-C or ``max_seconds``.

    Args:
        config: :class:`AppConfig`.
        generate: generate solutions before the loop; run: then start running (implies generate).
        plan: ``"pose"`` / ``"joints"``: plan to the goal point / configuration before the loop,
            which then plays the motion.
        max_seconds: wall-clock seconds from the printed URL to the end (the start-up generation
            included; a generation under way finishes first); ``None``: until Ctrl-C.
        out: where the two lines go (default ``sys.stdout``).

    Returns:
        0: the app ended normally, by ``max_seconds`` or by Ctrl-C (it prints "app stopped").
    """
    import logging
    import sys
    import time

    from drake_mh.viz.app import PlannerApp

    logger = logging.getLogger("drake_mh.viz.app")
    out = out if out is not None else sys.stdout
    app = None
    reason = "stopped by Ctrl-C"
    try:
        app = PlannerApp(config)
        started = time.monotonic()
        print(f"drake-mh app: open {app.page_url} in a browser (controls and 3-D view; Meshcat alone at "
              f"{app.meshcat.web_url()}; localhost only; Ctrl-C to stop)", file=out, flush=True)
        if generate or run:
            app.generate()
        if run:
            app.play("run")
        if plan is not None:
            app.planner.start(plan, wait=True)
        left = None if max_seconds is None else max(0.0, float(max_seconds) - (time.monotonic() - started))
        app.run(left)
        reason = "stopped" if max_seconds is None else f"stopped after --max-seconds {max_seconds:g}"
    except KeyboardInterrupt:
        pass
    finally:
        if app is not None:
            app.close()
    if app is None:
        print("drake-mh app: app stopped by Ctrl-C while starting", file=out, flush=True)
        return 0
    try:
        app._status(f"app {reason}: start drake-mh app again to continue")
    except Exception:  # noqa: BLE001 - Ctrl-C may have left the loop inside a Meshcat call
        logger.debug("could not write the final status", exc_info=True)
    state = app.state()
    fps = state["run_fps"]
    print(f"drake-mh app: app {reason} ({state['elapsed']:.0f} s, {state['events']} regeneration events"
          + (f", {fps:.1f} frames/s while running)" if fps else ")"), file=out, flush=True)
    return 0
