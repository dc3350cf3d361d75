"""``drake-mh study`` and ``drake-mh report`` subcommands."""

from __future__ import annotations

import argparse
import contextlib
import logging
import time

from drake_mh.errors import InvalidArgument
from drake_mh.study.machine import machine_line

logger = logging.getLogger(__name__)


def _non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}")
    return value


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``study`` and ``report``."""
    p = subparsers.add_parser(
        "study",
        parents=[common],
        help="run (or resume) a study and write its report",
        description="Run a study from the studies/ folder (or a path to a study .py file). "
        "Finished cases are kept: re-running the same command resumes. See docs/studies.md.",
    )
    p.add_argument("name", help="study name in studies/ or path to a study .py file ('list' lists them)")
    p.add_argument("--quick", action="store_true", help="run the small quick grid (seconds to minutes)")
    p.add_argument("--workers", type=_non_negative_int, default=None, help="local worker processes (default: CPU count; 0 = in this process)")
    p.add_argument("--executor", default=None, metavar="URL", help="'local' (default), 'serial' or dask://HOST:PORT")
    p.add_argument("--out", default=None, metavar="DIR", help="results folder (default results/NAME, results/NAME-quick)")
    p.add_argument("--seed", type=_non_negative_int, default=None, help="study seed (default: the study's own)")
    p.add_argument("--first-by", default=None, metavar="KEYS",
                   help="comma-separated grid keys to run in order first, e.g. 'rep': every cell's first "
                        "replicate before any second one (a partial run stays balanced)")
    p.add_argument("--no-report", action="store_true", help="do not write report.md / index.html at the end")
    p.add_argument("--strict", action="store_true", help="exit with code 1 when a case raised")
    p.set_defaults(func=cmd_study)

    r = subparsers.add_parser(
        "report",
        parents=[common],
        help="write report.md and index.html for a results folder",
        description="(Re)write report.md, index.html and figures/ of a results folder, complete or partial.",
    )
    r.add_argument("dir", help="results folder (contains records.jsonl)")
    r.set_defaults(func=cmd_report)


@contextlib.contextmanager
def _progress_logging(enabled: bool):
    if not enabled:
        yield
        return
    from tqdm.contrib.logging import logging_redirect_tqdm

    with logging_redirect_tqdm():
        yield


REUSE_HINT = "to recompute them, move that folder aside or give another --out"


def run_and_print(name: str, args: argparse.Namespace, out=None, quick=None, reuse_hint: str | None = REUSE_HINT) -> object:
    """Runs one study with the CLI options and prints its outcome; returns the StudyResult.

    Args:
        name: study name or path (``"list"`` prints the available studies).
        args: the parsed CLI options.
        out, quick: override ``args.out`` / ``args.quick``.
        reuse_hint: printed after the count of finished cases that were reused (not run
            again); ``None`` prints no such line (the demo says it once for all studies).
    """
    from drake_mh.cli.options import wants_progress
    from drake_mh.study import available_studies, run_study

    if name == "list":
        for study_name in available_studies():
            print(study_name)
        return None
    if args.workers is not None and args.executor and not args.executor.startswith(("local", "process")):
        raise InvalidArgument("--workers applies to local worker processes; drop it when using --executor")
    progress = wants_progress(args)
    start = time.perf_counter()
    with _progress_logging(progress):
        result = run_study(
            name,
            quick=args.quick if quick is None else quick,
            out=out if out is not None else args.out,
            executor=args.executor,
            workers=args.workers,
            seed=args.seed,
            progress=progress,
            report=not getattr(args, "no_report", False),
            first_by=tuple(k.strip() for k in args.first_by.split(",")) if getattr(args, "first_by", None) else None,
        )
    elapsed = time.perf_counter() - start
    quiet = getattr(args, "quiet", False)
    already = result.n_cases - result.n_new if result.complete else len(result.records) - result.n_new
    line = f"study {result.study}: {len(result.records)}/{result.n_cases} cases ({result.n_new} run now"
    line += f", {already} already done" if already else ""
    line += f", {result.n_errors} raised" if result.n_errors else ""
    line += f") in {elapsed:.1f} s -> {result.folder}"
    if not quiet:
        print(line)
        machine = machine_line(result.records)
        if machine:
            print(machine)
        if already and reuse_hint:
            print(f"({already} finished cases were reused from {result.folder}, not run again; {reuse_hint})")
        if result.summary.strip():
            print(result.summary.rstrip())
        if result.n_errors:
            print(f"{result.n_errors} case(s) raised; they are listed in the report")
    if result.report is not None:
        print(f"report: {result.report}")
    return result


def cmd_study(args: argparse.Namespace) -> int:
    """``drake-mh study NAME ...``."""
    result = run_and_print(args.name, args)
    if result is not None and args.strict and result.n_errors:
        return 1
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    """``drake-mh report DIR``."""
    from drake_mh.study import write_report

    print(f"report: {write_report(args.dir)}")
    return 0
