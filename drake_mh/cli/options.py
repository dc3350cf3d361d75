"""What several ``drake-mh`` commands share: robot and retiming options, output paths, progress bars."""

from __future__ import annotations

import argparse
import os
import sys

__all__ = ["add_robot_options", "load_robot_from_args", "add_retime_options", "check_output_path",
           "register_robot_options", "wants_progress"]


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
    """``load_robot(args.robot or name, ee_frame=args.ee_frame, packages=--package ...,
    limits=--limits)``."""
    import drake_mh
    from drake_mh.robot.packages import parse_package_option

    return drake_mh.load_robot(name if name is not None else args.robot,
                               ee_frame=getattr(args, "ee_frame", None),
                               packages=parse_package_option(getattr(args, "package", None)) or None,
                               limits=getattr(args, "limits", None))


def add_retime_options(p: argparse.ArgumentParser) -> None:
    """``--limits PATH``, ``--velocity-scaling F``, ``--acceleration-scaling F``, ``--rate HZ``
    for commands that retime a motion."""
    p.add_argument("--limits", default=None, metavar="PATH",
                   help="a MoveIt-style joint_limits.yaml: velocity, acceleration, jerk, effort limits per joint "
                        "(and default scaling factors); default: what the model declares")
    p.add_argument("--velocity-scaling", type=float, default=None, metavar="F",
                   help="fraction of the velocity limits to use, in (0, 1] (MoveIt's factor; default 1 or the "
                        "limits file's)")
    p.add_argument("--acceleration-scaling", type=float, default=None, metavar="F",
                   help="fraction of the acceleration limits to use, in (0, 1] (MoveIt's factor)")
    p.add_argument("--rate", type=float, default=100.0, metavar="HZ",
                   help="samples per second written by --out (default 100; the last sample is the end)")


def check_output_path(path: str, option: str, formats=None):
    """``path`` as a ``Path`` after checking that a file can be written there (before any long
    work): not a folder, its nearest existing folder writable, no file where a folder must be;
    ``formats``: the extensions accepted.

    Raises:
        InvalidArgument: the message names the option, the path and what is wrong.
    """
    from pathlib import Path

    from drake_mh.errors import InvalidArgument

    target = Path(path).expanduser()
    if formats is not None and target.suffix.lower() not in formats:
        raise InvalidArgument(f"{option} {path}: unknown file type {target.suffix!r}; use {', '.join(formats)}")
    if target.is_dir():
        raise InvalidArgument(f"{option} {path}: is a folder; give a file name")
    if target.exists() and not os.access(target, os.W_OK):
        raise InvalidArgument(f"{option} {path}: the file is not writable")
    folder = target.parent
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise InvalidArgument(f"{option} {path}: {folder} is a file, not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InvalidArgument(f"{option} {path}: the folder {folder} is not writable")
    return target


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
