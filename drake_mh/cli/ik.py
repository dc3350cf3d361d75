"""``drake-mh ik``: solve one IK problem from the command line.

Example::

    drake-mh ik --robot panda --position 0.5 0.1 0.4 --rpy 3.1416 0 0 --method hybrid --json
    drake-mh ik --robot path/to/ur5.urdf --ee-frame tool0 --package ur_description=DIR --position 0.4 0.1 0.3

Prints the verified result (``--json``: one JSON object). Exit code 0 when the result is
verified successful, 1 when the method failed to find a solution, 2 for bad input (unknown
robot or method, malformed numbers: one line naming the valid choices).
"""

from __future__ import annotations

import argparse
import json

__all__ = ["register", "cmd_ik"]


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``ik``."""
    p = subparsers.add_parser(
        "ik",
        parents=[common],
        help="solve inverse kinematics for one target (any method; verified with Drake)",
        description="Solve IK for a target position (and orientation with --rpy) with any method of "
        "drake_mh.ik.available_ik_methods(): the library's metaheuristics, 'hybrid', 'pinv', 'dls', "
        "'drake_snopt', 'drake_ipopt'. Success is verified with Drake (FK, limits). Exit code 0: "
        "verified solution; 1: no solution found; 2: bad input.",
    )
    p.add_argument("--robot", default="panda",
                   help="bundled robot name or model file: .urdf, .xacro, .sdf, MJCF .xml (default panda)")
    from drake_mh.cli.options import add_robot_options

    add_robot_options(p)
    p.add_argument("--position", nargs=3, type=float, required=True, metavar=("X", "Y", "Z"),
                   help="target position of the end effector in the world frame [m]")
    p.add_argument("--rpy", nargs=3, type=float, default=None, metavar=("R", "P", "Y"),
                   help="target roll-pitch-yaw [rad]; omit for position-only IK")
    p.add_argument("--method", default="hybrid", help="IK method (default hybrid)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--timeout", type=float, default=1.0, help="time limit [s] (default 1)")
    p.add_argument("--budget", type=int, default=None, help="evaluations (solver starts for drake_*)")
    p.add_argument("--position-tolerance", type=float, default=None, metavar="M",
                   help="[m] (default 1e-3 position-only, 1e-5 with --rpy)")
    p.add_argument("--orientation-tolerance", type=float, default=None, metavar="RAD",
                   help="[rad] (default 1e-2 position-only, 1e-5 with --rpy)")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.set_defaults(func=cmd_ik)


def cmd_ik(args: argparse.Namespace) -> int:
    """``drake-mh ik``: returns 0 on a verified solution, 1 otherwise."""
    import drake_mh
    from drake_mh.errors import UnknownMethod
    from drake_mh.ik import IKProblem, available_ik_methods, solve_ik

    methods = available_ik_methods()
    if args.method.lower() not in methods:  # before loading the robot: fail fast
        raise UnknownMethod(args.method, methods, what="IK method")
    from drake_mh.cli.options import load_robot_from_args

    robot = load_robot_from_args(args)
    pose = args.rpy is not None
    tol_p = args.position_tolerance if args.position_tolerance is not None else (1e-5 if pose else 1e-3)
    tol_o = args.orientation_tolerance if args.orientation_tolerance is not None else (1e-5 if pose else 1e-2)
    problem = IKProblem(robot, args.position, rpy=args.rpy, position_tolerance=tol_p, orientation_tolerance=tol_o)
    result = solve_ik(problem, args.method, seed=args.seed, budget=args.budget, timeout=args.timeout)
    if args.json:
        data = result.to_dict()
        data.update(robot=robot.name, joint_names=list(robot.joint_names), target_position=list(args.position),
                    target_rpy=None if args.rpy is None else list(args.rpy),
                    position_tolerance=tol_p, orientation_tolerance=tol_o)
        print(json.dumps(data))
    else:
        state = "success" if result.success else "FAILED"
        loading = f"; {result.prepare_time:.2f} s loading kernels first" if result.prepare_time else ""
        print(f"{state}: {result.method} on {robot.name} in {result.time * 1e3:.2f} ms{loading} ({result.message})")
        print(f"  q = [{', '.join(f'{v:.6f}' for v in result.q)}]")
        print(f"  position error {result.position_error:.3g} m (tol {tol_p:g}), orientation error "
              f"{result.orientation_error:.3g} rad (tol {tol_o:g}), within limits: {result.within_limits}")
    return 0 if result.success else 1
