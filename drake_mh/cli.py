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
    "drake_mh.viz.cli",  # app (from the visualisation issue)
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


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds the ``robots`` subcommand."""
    p = subparsers.add_parser(
        "robots",
        parents=[common],
        help="list the bundled robots (or show one)",
        description="List the bundled robots with their joint count and limits; with NAME, "
        "show one robot (a bundled name or a .urdf path); --check runs the FK/Jacobian/distance "
        "smoke test against Drake.",
    )
    p.add_argument("name", nargs="?", help="bundled robot name or path to a .urdf file")
    p.add_argument("--check", action="store_true", help="run the smoke test (FK, Jacobian, distances)")
    p.set_defaults(func=cmd_robots)


def _robot_line(name: str) -> str:
    import numpy as np

    import drake_mh

    robot = drake_mh.load_robot(name)
    limits = ", ".join(f"[{lo:+.2f}, {hi:+.2f}]" for lo, hi in zip(np.asarray(robot.lower), np.asarray(robot.upper)))
    return f"{name:<16} nq={robot.nq:<3} limits [rad]: {limits}"


def cmd_robots(args: argparse.Namespace) -> int:
    """``drake-mh robots [NAME] [--check]``."""
    import drake_mh

    if args.check:
        smoke = _smoke()
        if smoke is None:
            raise DrakeMhError("the smoke test (drake_mh.smoke.run_smoke) is not available in this version")
        smoke(out=print)
        return 0
    names = [args.name] if args.name else drake_mh.available_robots()
    for name in names:
        print(_robot_line(name))
    return 0


def _smoke():
    module = _load_command_module("drake_mh.smoke")
    return getattr(module, "run_smoke", None) if module is not None else None


def _no_command(parser: argparse.ArgumentParser) -> int:
    """Without a subcommand: the robot catalogue / smoke test, then the usage."""
    smoke = _smoke()
    try:
        if smoke is not None:
            smoke(out=print)
        else:
            cmd_robots(argparse.Namespace(name=None, check=False))
    except DrakeMhError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
    print()
    parser.print_help()
    return 0


# --- entry point -------------------------------------------------------------------------


def _configure_logging(verbose: bool, quiet: bool) -> None:
    level = logging.DEBUG if verbose else (logging.ERROR if quiet else logging.WARNING)
    root = logging.getLogger()
    if not any(getattr(h, "_drake_mh", False) for h in root.handlers):
        handler = logging.StreamHandler(sys.stderr)
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
        print(f"{PROG}: interrupted; run the same command again to continue where it stopped", file=sys.stderr)
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
