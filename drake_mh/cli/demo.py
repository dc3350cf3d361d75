"""``drake-mh demo``: the quick form of the demo studies one after the other, then a report
page with their figures, a 3-D animation and links to each study's report. What it runs and the
page it writes are the library's (:mod:`drake_mh.study.demo`); ``--fresh`` first moves earlier
results aside, else finished cases are reused (and said so).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from drake_mh.errors import InvalidArgument
from drake_mh.study.demo import (BACKGROUND_COMPILE, DEMO_STUDIES, OPTIONAL_DEMO_STUDIES, demo_studies, earlier_results,
                                 mark_folder, move_aside, reuse_message, study_section, write_page)

__all__ = ["register", "cmd_demo"]


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``demo``."""
    p = subparsers.add_parser(
        "demo",
        parents=[common],
        help="short end-to-end comparison with a report (a few minutes at most)",
        description="Run the quick form of the demo studies ("
        + ", ".join(DEMO_STUDIES + OPTIONAL_DEMO_STUDIES)
        + ") and write a report with their figures, a 3-D animation and links to each study "
        "report. Re-running reuses the finished cases (and says how many); --fresh runs "
        "everything again after moving the earlier results aside.",
    )
    p.add_argument("--out", default="results/demo", metavar="DIR", help="results folder (default results/demo)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: CPU count)")
    p.add_argument("--fresh", action="store_true",
                   help="run every case again: the earlier results in DIR are first moved to "
                        "DIR-<date>-<time> (kept, not deleted)")
    p.set_defaults(func=cmd_demo, executor=None, seed=None, quick=True, no_report=False)


def cmd_demo(args: argparse.Namespace) -> int:
    """``drake-mh demo``."""
    from drake_mh.cli.robots import run_smoke
    from drake_mh.cli.study import run_and_print
    from drake_mh.study import warmup

    if args.workers is not None and args.workers < 0:
        raise InvalidArgument(f"--workers must be >= 0, got {args.workers}")
    start = time.perf_counter()
    out = Path(args.out)
    quiet = getattr(args, "quiet", False)
    studies = demo_studies()
    if args.fresh:
        moved = move_aside(out, studies)
        if moved is not None:
            print(f"--fresh: earlier results moved to {moved} (kept); running every case again")
    earlier = earlier_results(out, studies)
    if earlier.total:
        print(reuse_message(out, earlier))
    if not quiet:
        run_smoke(out=print)
        print()
    mark_folder(out, studies)
    # motion_benchmark's kernels compile on the second core while the other studies run
    compiling = warmup.start() if BACKGROUND_COMPILE in studies and not earlier.cases.get(BACKGROUND_COMPILE) else []
    sections, results = [], []
    for name in studies:
        if name == BACKGROUND_COMPILE:
            warmup.wait(compiling)
        if not quiet:
            print(f"== {name} (quick) ==")
        result = run_and_print(name, args, out=out / name, quick=True, reuse_hint=None)
        results.append(result)
        sections.append(study_section(out, name, result))
        if not quiet:
            print()
    elapsed = time.perf_counter() - start
    page = write_page(out, sections, results, elapsed)
    reused = sum(len(r.records) - r.n_new for r in results)
    errors = sum(r.n_errors for r in results)
    print(f"demo finished in {elapsed:.1f} s" + (f" ({errors} case(s) raised)" if errors else "")
          + (f"; {reused} cases reused from the earlier run (--fresh recomputes them)" if reused else ""))
    print(f"demo report: {page.resolve()}")
    return 0
