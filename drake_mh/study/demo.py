"""``drake-mh demo``: a short end-to-end comparison on built-in defaults, with a report.

Runs the quick form of the demo studies one after the other (each resumes if already run
into the same folder), then writes ``<out>/index.html`` linking every study report. The
studies are found like ``drake-mh study`` finds them (``studies/`` of the repository).
"""

from __future__ import annotations

import argparse
import logging
import shutil
import time
from pathlib import Path

from drake_mh.errors import InvalidArgument

logger = logging.getLogger(__name__)

#: studies the demo runs (quick grid), in order; the IK comparison joins when it exists
DEMO_STUDIES: tuple[str, ...] = ("bench_kinematics", "fk_accuracy", "retime_benchmark")
#: optional studies added to the demo when their script exists
OPTIONAL_DEMO_STUDIES: tuple[str, ...] = ("ik_comparison",)


def register(subparsers, common: argparse.ArgumentParser) -> None:
    """Adds ``demo``."""
    p = subparsers.add_parser(
        "demo",
        parents=[common],
        help="short end-to-end comparison with a report (a few minutes at most)",
        description="Run the quick form of the demo studies ("
        + ", ".join(DEMO_STUDIES)
        + ") and write a report linking them. Re-running continues (and reuses finished cases) "
        "unless --fresh is given.",
    )
    p.add_argument("--out", default="results/demo", metavar="DIR", help="results folder (default results/demo)")
    p.add_argument("--workers", type=int, default=None, help="local worker processes (default: CPU count)")
    p.add_argument("--fresh", action="store_true", help="delete the demo's previous results first")
    p.set_defaults(func=cmd_demo, executor=None, seed=None, quick=True, no_report=False)


def demo_studies() -> list[str]:
    """The demo's studies that exist in the studies folders."""
    from drake_mh.study import available_studies

    found = set(available_studies())
    return list(DEMO_STUDIES) + [s for s in OPTIONAL_DEMO_STUDIES if s in found]


def _clear(folder: Path) -> None:
    """Deletes a previous study results folder (only if it is one)."""
    if folder.is_dir():
        if not (folder / "study.json").is_file():
            raise InvalidArgument(f"{folder} exists but is not a study results folder; choose another --out")
        shutil.rmtree(folder)


def cmd_demo(args: argparse.Namespace) -> int:
    """``drake-mh demo``."""
    from drake_mh.cli import _smoke
    from drake_mh.study.commands import run_and_print
    from drake_mh.study.report.document import Document, Heading, Link, Markdown, Paragraph, to_html, to_markdown
    from drake_mh.study.store import write_atomic

    if args.workers is not None and args.workers < 0:
        raise InvalidArgument(f"--workers must be >= 0, got {args.workers}")
    start = time.perf_counter()
    out = Path(args.out)
    quiet = getattr(args, "quiet", False)
    smoke = _smoke()
    if smoke is not None and not quiet:
        smoke(out=print)
        print()
    doc = Document(title="drake_mh demo")
    doc.add(
        Paragraph(
            "Quick forms of the demo studies, run end to end on the bundled robots. Each study has "
            "its own report (tables, statistics, figures) linked below."
        )
    )
    results = []
    for name in demo_studies():
        folder = out / name
        if args.fresh:
            _clear(folder)
        if not quiet:
            print(f"== {name} (quick) ==")
        result = run_and_print(name, args, out=folder, quick=True)
        results.append(result)
        doc.add(Heading(name))
        if result.summary.strip():
            doc.add(Markdown(result.summary))
        line = f"{len(result.records)}/{result.n_cases} cases"
        line += f", {result.n_errors} raised" if result.n_errors else ""
        doc.add(Paragraph(line + "."))
        doc.add(Link(f"{name}/index.html", f"{name} report"))
        if not quiet:
            print()
    elapsed = time.perf_counter() - start
    doc.add(Paragraph(f"Demo wall time {elapsed:.1f} s."))
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "report.md", to_markdown(doc).encode("utf-8"))
    write_atomic(out / "index.html", to_html(doc).encode("utf-8"))
    errors = sum(r.n_errors for r in results)
    print(f"demo finished in {elapsed:.1f} s" + (f" ({errors} case(s) raised)" if errors else ""))
    print(f"demo report: {(out / 'index.html').resolve()}")
    return 0
