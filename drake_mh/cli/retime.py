"""``drake-mh retime``: a joint path from a file, retimed and certified, written for a controller.

Example::

    drake-mh retime path.csv --robot arm.urdf --ee-frame tool0 --out motion.json
    drake-mh retime path.csv --robot panda --method ruckig --limits joint_limits.yaml --out motion.csv

The waypoints file (CSV): one waypoint per row, one number per joint [rad or m], separated by
commas; an optional first row of joint names (then the columns may come in any order and are
matched by name; without it, the columns follow the robot's joint order, ``drake-mh robots
NAME`` lists it); blank lines and lines starting with ``#`` are skipped. The path is retimed
(:func:`drake_mh.trajectories.retime`: toppra by default) under the robot's limits (``--limits``
a MoveIt ``joint_limits.yaml``; ``--velocity-scaling`` / ``--acceleration-scaling``), certified,
and written to ``--out`` by its extension (``.json`` / ``.yaml``: ROS 2 ``JointTrajectory``
shape; ``.csv``), sampled at ``--rate``. Collisions are not checked (there is no scene): plan
with ``drake-mh plan`` for that.

Exit code 0 when written, 2 for bad input (one line saying what is wrong).
"""

from __future__ import annotations

import argparse
import csv
import json
import sys

__all__ = ["register", "cmd_retime", "read_waypoints"]


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``retime``."""
    from drake_mh.cli.options import add_retime_options, add_robot_options

    p = subparsers.add_parser(
        "retime",
        parents=[common],
        help="retime a joint path from a CSV file under the robot's limits; certify it; write it for a controller",
        description="Read joint waypoints (CSV: one row per waypoint, optional header of joint names), retime "
        "them under the robot's limits (toppra or ruckig; a vendor URDF without acceleration limits is retimed "
        "under its velocity and torque limits), certify the trajectory, and write it sampled at --rate to --out "
        "(.json / .yaml: ROS 2 JointTrajectory shape; .csv). Prints where every enforced limit came from. "
        "Collisions are not checked. Exit code 0: written; 2: bad input.",
    )
    p.add_argument("waypoints", metavar="WAYPOINTS.csv", help="joint waypoints, one row each [rad or m]")
    p.add_argument("--robot", required=True, help="bundled robot name or model file")
    add_robot_options(p)
    add_retime_options(p)
    p.add_argument("--method", choices=("toppra", "ruckig", "drake-toppra"), default="toppra",
                   help="toppra (default; spline through the waypoints, jerk not limited), ruckig (jerk-limited, "
                        "straight segments, at rest at each waypoint) or drake-toppra")
    p.add_argument("--out", required=True, metavar="FILE", help="where to write the trajectory (.json, .yaml, .csv)")
    p.add_argument("--json", action="store_true", help="print a summary as one JSON object")
    p.set_defaults(func=cmd_retime)


def read_waypoints(path, joint_names) -> tuple:
    """``(W (K, nq), reordered)`` from a waypoints CSV (module docstring); ``reordered``: whether a
    header put the columns in the robot's order.

    Raises:
        InvalidArgument: unreadable file, unknown or missing joint names, a row of the wrong
            length or with a non-number (the message names the line).
    """
    import numpy as np

    from drake_mh.errors import InvalidArgument

    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = [(k + 1, [c.strip() for c in row]) for k, row in enumerate(csv.reader(handle))]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InvalidArgument(f"cannot read the waypoints {path}: {exc}") from exc
    rows = [(k, row) for k, row in rows if row and any(row) and not row[0].startswith("#")]
    if not rows:
        raise InvalidArgument(f"{path}: no waypoints (one row per waypoint, {len(joint_names)} numbers each)")
    order = list(range(len(joint_names)))
    reordered = False
    if not _is_number(rows[0][1][0]):
        header = rows.pop(0)[1]
        unknown = [n for n in header if n not in joint_names]
        missing = [n for n in joint_names if n not in header]
        if unknown or missing or len(header) != len(joint_names):
            raise InvalidArgument(f"{path}: the header must name each of the robot's joints once ({', '.join(joint_names)}); "
                                  f"unknown: {unknown}, missing: {missing}")
        order = [header.index(n) for n in joint_names]
        reordered = order != list(range(len(joint_names)))
    W = []
    for line, row in rows:
        if len(row) != len(joint_names):
            raise InvalidArgument(f"{path}, line {line}: {len(row)} values for {len(joint_names)} joints "
                                  f"({', '.join(joint_names)})")
        if not all(_is_number(c) for c in row):
            raise InvalidArgument(f"{path}, line {line}: every value must be a number [rad or m], got {row}")
        W.append([float(row[i]) for i in order])
    W = np.asarray(W, dtype=float)
    if len(W) < 2:
        raise InvalidArgument(f"{path}: a path needs at least 2 waypoints, got {len(W)}")
    if not np.all(np.isfinite(W)):
        raise InvalidArgument(f"{path}: the waypoints contain NaN or inf")
    return W, reordered


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def cmd_retime(args: argparse.Namespace) -> int:
    """``drake-mh retime``: returns 0 when the trajectory is written."""
    import numpy as np

    from drake_mh.cli.options import check_output_path, load_robot_from_args
    from drake_mh.planning.verify import check_scaling
    from drake_mh.trajectories import retime
    from drake_mh.trajectories.export import FORMATS, sample_times

    out = check_output_path(args.out, "--out", FORMATS)
    sample_times(1.0, args.rate)  # the rate's check, before any work
    check_scaling(args.velocity_scaling, args.acceleration_scaling)
    robot = load_robot_from_args(args)
    W, _ = read_waypoints(args.waypoints, list(robot.joint_names))
    traj = retime(W, robot, args.method, velocity_scaling=args.velocity_scaling,
                  acceleration_scaling=args.acceleration_scaling)
    samples = traj.save(out, robot, args.rate)
    cert = traj.info["certificate"]
    table = traj.info["enforced_limits"]
    if args.json:
        print(json.dumps({"robot": robot.name, "method": traj.method, "waypoints": int(len(W)),
                          "duration": traj.duration, "samples": len(samples), "rate_hz": args.rate, "out": str(out),
                          "max_ratio": cert.max_ratio(cert.enforced), "limits": table.as_dict(),
                          "collision_checked": False}))
        return 0
    worst = cert.worst(cert.enforced)
    print(f"retimed with {traj.method}: {len(W)} waypoints, {traj.duration:.3f} s; certified within the enforced "
          f"limits (worst: {worst[0]} of {worst[1]} at {100 * worst[3]:.1f} %); collisions not checked (no scene)")
    print("limits enforced (value per joint | where it came from):")
    for line in table.summary():
        print(f"  {line}")
    print(f"trajectory written to {out} ({len(samples)} samples at {args.rate:g} Hz, "
          f"max |q̇| {np.max(cert.bounds['velocity']):.3g} rad/s)", file=sys.stdout)
    return 0
