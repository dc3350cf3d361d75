"""The ``drake-mh`` command line.

Each subcommand lives in a module with a ``register(subparsers, common)`` function that adds
its parser (``subparsers.add_parser(NAME, parents=[common], ...)``) and sets
``func=handler`` where ``handler(args) -> int`` returns the exit code. To add a subcommand,
create the module and list it in :data:`COMMAND_MODULES`; a listed module that does not
exist yet is skipped, so ``ik`` and ``app`` appear as soon as their modules are written.

Exit codes: 0 success, 1 internal error, 2 bad usage or input (one line on stderr naming
the valid choices; ``--verbose`` adds the traceback), 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
import traceback
from collections.abc import Sequence

from drake_mh.errors import DrakeMhError

logger = logging.getLogger(__name__)

PROG = "drake-mh"

#: subcommand modules in help order; each defines ``register(subparsers, common)``
COMMAND_MODULES: tuple[str, ...] = (
    "drake_mh.cli",  # robots
    "drake_mh.ik.cli",  # ik (from the IK issue)
    "drake_mh.study.commands",  # study, report
    "drake_mh.study.demo",  # demo
    "drake_mh.study.warmup_cli",  # warmup (compile every kernel ahead)
    "drake_mh.viz.cli",  # app (from the visualisation issue)
    "drake_mh.viz.plan_cli",  # plan (one motion: issue #18)
)


class UsageError(DrakeMhError, ValueError):
    """Bad command-line usage (unknown subcommand, option or value)."""


class _Parser(argparse.ArgumentParser):
    """ArgumentParser that raises :class:`UsageError` instead of printing usage and exiting."""

    def error(self, message: str):  # noqa: D102
        raise UsageError(f"{message} (see `{self.prog} --help`)")


def _common_options() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS, help="debug logging and tracebacks")
    common.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress bar, only essential output")
    return common


def _load_command_module(name: str):
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        parts = name.split(".")
        missing = {".".join(parts[: i + 1]) for i in range(len(parts))}
        if exc.name in missing:
            return None  # not written yet: the subcommand is simply absent
        raise


def build_parser() -> argparse.ArgumentParser:
    """Builds the ``drake-mh`` parser with every available subcommand."""
    parser = _Parser(
        prog=PROG,
        description="Metaheuristic and gradient motion planning side by side on Drake: "
        "robots, studies, reports.",
        epilog="Run `drake-mh demo` for a short end-to-end comparison with a report.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", default=False, help="debug logging and tracebacks")
    parser.add_argument("-q", "--quiet", action="store_true", default=False, help="no progress bar, only essential output")
    from drake_mh import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    common = _common_options()
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMAND_MODULES:
        module = sys.modules[__name__] if name == __name__ else _load_command_module(name)
        if module is not None:
            module.register(subparsers, common)
    return parser


# --- robots -------------------------------------------------------------------------------


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
    from drake_mh.packages import parse_package_option

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
    from drake_mh.packages import parse_package_option
    from drake_mh.robot import register_robot

    packages = parse_package_option(getattr(args, "package", None)) or None
    for name in names:
        if name in drake_mh.available_robots():
            continue
        if not Path(name).expanduser().is_file():
            raise UnknownRobot(name, drake_mh.available_robots())
        register_robot(str(name), name, ee_frame=getattr(args, "ee_frame", None), packages=packages)


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds the ``robots`` subcommand."""
    p = subparsers.add_parser(
        "robots",
        parents=[common],
        help="the robot catalogue and smoke test, or one robot's entry (bundled name or model file)",
        description="Without NAME: the catalogue of the bundled robots and the smoke test (batched "
        "kernel vs Drake FK/Jacobian, sphere model vs exact distances). With NAME (a bundled name or "
        "the path of a .urdf, .xacro, .sdf or MJCF .xml file): that robot's entry: DOF, joints and "
        "limits, end effector, locked joints, collision geometry per link, sphere model and bound.",
    )
    p.add_argument("name", nargs="?", metavar="PATH_OR_NAME", help="bundled robot name or model file")
    add_robot_options(p)
    p.add_argument("--check", action="store_true",
                   help="also run the smoke test (FK, Jacobian, distances) on that robot")
    p.set_defaults(func=cmd_robots)


def cmd_robots(args: argparse.Namespace) -> int:
    """``drake-mh robots [PATH_OR_NAME] [--ee-frame NAME] [--package NAME=DIR] [--check]``."""
    from drake_mh.errors import InvalidArgument
    from drake_mh.smoke import _short, catalogue_entry, kernel_errors, run_smoke, sphere_check

    if args.name is None:
        if args.ee_frame or args.package:
            raise InvalidArgument("--ee-frame and --package describe one robot: give its PATH_OR_NAME "
                                  "(drake-mh robots path/to/robot.urdf --ee-frame tool0)")
        run_smoke(out=print)
        return 0
    robot = load_robot_from_args(args, args.name)
    for line in catalogue_entry(robot):
        print(line)
    if args.check:
        fk_err, jac_err = kernel_errors(robot)
        print(f"  smoke test, batched kernel vs Drake on 200 random configurations: max|ΔFK| "
              f"{fk_err:.1e}, max|ΔJ| {jac_err:.1e}")
        try:
            s = sphere_check(robot)
            print(f"  sphere model vs exact distance to a sphere obstacle (50 configurations): worst "
                  f"gap {s['worst_gap']:.4f} m, {s['collisions']} collisions, {s['missed']} missed")
        except DrakeMhError as exc:
            print(f"  sphere model vs exact distance: not available ({_short(exc)})")
    return 0


def _smoke():
    module = _load_command_module("drake_mh.smoke")
    return getattr(module, "run_smoke", None) if module is not None else None


def _no_command(parser: argparse.ArgumentParser) -> int:
    """Without a subcommand: the robot catalogue and smoke test, then one line on the commands."""
    smoke = _smoke()
    try:
        if smoke is not None:
            smoke(out=print)
    except DrakeMhError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `python -m drake_mh | head`
        return 0
    commands = ", ".join(parser._subparsers._group_actions[0].choices)  # noqa: SLF001
    print()
    print(f"Commands: {commands}. `{PROG} --help` or `{PROG} COMMAND --help` for usage; "
          f"`{PROG} demo` runs a short end-to-end comparison with a report.")
    return 0


# --- entry point -------------------------------------------------------------------------


class _StderrHandler(logging.StreamHandler):
    """A handler that writes to ``sys.stderr`` as it is when a record comes, not as it was when
    the handler was made: a caller that swaps ``sys.stderr`` (a test runner capturing output, a
    notebook) and closes the old one then gets no "I/O operation on closed file" errors."""

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value):  # StreamHandler.__init__ sets it; the property always reads sys.stderr
        pass


def _configure_logging(verbose: bool, quiet: bool) -> None:
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.WARNING)
    root = logging.getLogger()
    if not any(getattr(h, "_drake_mh", False) for h in root.handlers):
        handler = _StderrHandler()
        handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
        handler._drake_mh = True  # type: ignore[attr-defined]
        root.addHandler(handler)
    root.setLevel(level if verbose else logging.WARNING)
    logging.getLogger("drake_mh").setLevel(level)


def wants_progress(args: argparse.Namespace) -> bool:
    """Progress bars only on an interactive terminal, not under ``--quiet`` or in CI logs."""
    if getattr(args, "quiet", False):
        return False
    if os.environ.get("CI") or os.environ.get("DRAKE_MH_NO_PROGRESS"):
        return False
    return sys.stderr.isatty()


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``drake-mh``; returns the exit code (the console script exits with it)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    verbose = "-v" in argv or "--verbose" in argv
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0)
    except DrakeMhError as exc:
        if verbose:
            traceback.print_exc()
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    verbose = bool(getattr(args, "verbose", False))
    _configure_logging(verbose, bool(getattr(args, "quiet", False)))
    if args.command is None:
        return _no_command(parser)
    try:
        return int(args.func(args) or 0)
    except DrakeMhError as exc:
        if verbose:
            traceback.print_exc()
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        resumable = args.command in ("study", "demo")  # studies keep every finished case
        tail = "; run the same command again to continue where it stopped" if resumable else ""
        print(f"{PROG} {args.command}: interrupted{tail}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `drake-mh robots | head -1`
        return 0
    except Exception as exc:  # noqa: BLE001 - one line unless --verbose
        if verbose:
            traceback.print_exc()
        print(
            f"{PROG}: internal error: {type(exc).__name__}: {exc} (run with --verbose for the traceback)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
