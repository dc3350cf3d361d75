"""What several ``drake-mh`` commands share: robot options and progress bars."""

from __future__ import annotations

import argparse
import os
import sys

__all__ = ["add_robot_options", "load_robot_from_args", "register_robot_options", "wants_progress"]


def add_robot_options(p: argparse.ArgumentParser, robot_help: str | None = None) -> None:
    """``--ee-frame NAME`` and ``--package NAME=DIR`` (repeatable), for robot-taking commands."""
    p.add_argument("--ee-frame", default=None, metavar="NAME",
                   help="end-effector frame of the robot (needed when the model has several tip "
                        "links, e.g. an arm with a hand); joints not on the way to it are locked")
    p.add_argument("--package", action="append", default=None, metavar="NAME=DIR",
                   help="folder of the package that package://NAME/... mesh references name "
                        "(repeatable; default: package.xml up the tree, ROS_PACKAGE_PATH, "
                        "AMENT_PREFIX_PATH, the model's folder and its parents)")


def load_robot_from_args(args: argparse.Namespace, name: str | None = None):
    """``load_robot(args.robot or name, ee_frame=args.ee_frame, packages=--package ...)``."""
    import drake_mh
    from drake_mh.robot.packages import parse_package_option

    return drake_mh.load_robot(name if name is not None else args.robot,
                               ee_frame=getattr(args, "ee_frame", None),
                               packages=parse_package_option(getattr(args, "package", None)) or None)


def register_robot_options(names, args: argparse.Namespace) -> None:
    """Check robot names/paths of a command and attach ``--ee-frame``/``--package`` to the paths.

    Commands that load robots later by name (the app's robot cycling) then get the options:
    each model path is registered under its own text with :func:`drake_mh.robot.register_robot`.

    Raises:
        UnknownRobot: a name is neither bundled nor an existing file.
    """
    from pathlib import Path

    import drake_mh
    from drake_mh.errors import UnknownRobot
    from drake_mh.robot import register_robot
    from drake_mh.robot.packages import parse_package_option

    packages = parse_package_option(getattr(args, "package", None)) or None
    for name in names:
        if name in drake_mh.available_robots():
            continue
        if not Path(name).expanduser().is_file():
            raise UnknownRobot(name, drake_mh.available_robots())
        register_robot(str(name), name, ee_frame=getattr(args, "ee_frame", None), packages=packages)


def wants_progress(args: argparse.Namespace) -> bool:
    """Progress bars only on an interactive terminal, not under ``--quiet`` or in CI logs."""
    if getattr(args, "quiet", False):
        return False
    if os.environ.get("CI") or os.environ.get("DRAKE_MH_NO_PROGRESS"):
        return False
    return sys.stderr.isatty()
