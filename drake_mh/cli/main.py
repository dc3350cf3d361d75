"""The ``drake-mh`` command line: its parser, :func:`main` with the exit codes, and
:func:`run_script` for a study script run by itself.

One module per command in this package (:data:`COMMANDS`, in help order), each with a
``register(subparsers, common)`` function that adds its parser
(``subparsers.add_parser(NAME, parents=[common], ...)``) and sets ``func=handler``, where
``handler(args) -> int`` returns the exit code. To add a command, write its module and list it
in :data:`COMMANDS`.

Exit codes: 0 success, 1 internal error, 2 bad usage or input (one line on stderr naming
the valid choices; ``--verbose`` adds the traceback), 130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import sys
import traceback
from collections.abc import Sequence
from typing import NoReturn

from drake_mh.cli import app, demo, ik, plan, retime, robots, study, warmup
from drake_mh.errors import DrakeMhError

logger = logging.getLogger(__name__)

PROG = "drake-mh"

COMMANDS = (robots, ik, study, demo, app, plan, retime, warmup)
"""The command modules, in help order (``study`` adds ``study`` and ``report``)."""
COMMAND_MODULES: tuple[str, ...] = tuple(module.__name__ for module in COMMANDS)
"""Their names."""


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
    for module in COMMANDS:
        module.register(subparsers, common)
    return parser


def _no_command(parser: argparse.ArgumentParser) -> int:
    """Without a subcommand: the robot catalogue and smoke test, then one line on the commands."""
    try:
        robots.run_smoke(out=print)
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


def run_script(study, argv: Sequence[str] | None = None) -> NoReturn:
    """``python studies/NAME.py [--quick] ...``: the same as ``drake-mh study <that file> ...``;
    exits the process with the command's exit code. A study script ends with::

        if __name__ == "__main__":
            from drake_mh.cli import run_script

            run_script(study)

    Args:
        study: the script's :class:`~drake_mh.study.Study` (the file defining its ``run``
            function is the one run) or a study name or path.
        argv: the options (default ``sys.argv[1:]``).
    """
    target = getattr(study, "source_file", None) or getattr(study, "name", study)
    raise SystemExit(main(["study", str(target), *(sys.argv[1:] if argv is None else argv)]))
