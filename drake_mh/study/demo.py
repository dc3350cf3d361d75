"""The demo (``drake-mh demo``, :mod:`drake_mh.cli.demo`): a short end-to-end comparison on
built-in defaults, with a report; what it runs and the page it writes.

The command runs the quick form of the demo studies one after the other, then writes
``<out>/index.html`` (:func:`write_page`):
one 3-D animation (a time-optimal Panda motion from ``retime_benchmark``), each study's summary
and key figures, and links to every study report. The studies are found like ``drake-mh study``
finds them (``studies/`` of the repository).

A second run into the same folder reuses the finished cases (the runner resumes) and says so,
on the terminal and on the page; ``--fresh`` first moves the earlier results aside (to
``<out>-<date>-<time>``, never deleted) and runs everything again.
"""

from __future__ import annotations

import datetime
import json
import logging
from dataclasses import dataclass
from pathlib import Path

from drake_mh.errors import InvalidArgument

logger = logging.getLogger(__name__)

#: studies the demo runs (quick grid), in order; the IK comparison joins when it exists
DEMO_STUDIES: tuple[str, ...] = ("bench_kinematics", "fk_accuracy", "retime_benchmark")
#: optional studies added to the demo when their script exists
OPTIONAL_DEMO_STUDIES: tuple[str, ...] = ("ik_comparison", "motion_benchmark")
#: the study whose numba kernels compile in two background processes from the demo's start
#: (:mod:`drake_mh.study.warmup`) where the compiled core is not built (with it, they run in C++)
BACKGROUND_COMPILE = "motion_benchmark"
#: figures of a study report shown on the demo page, in order of preference (at most two)
KEY_FIGURES: tuple[str, ...] = ("boxplots", "convergence")
#: the demo page's 3-D animation: (study, robot, first method name prefix, title)
DEMO_ANIMATION = (
    "retime_benchmark", "panda", "toppra@",
    "Time-optimal Panda motion (toppra, from retime_benchmark) under velocity, acceleration and "
    "torque limits; drag to rotate, scroll to zoom",
)
#: marker file written into the demo folder (tells --fresh the folder is the demo's)
MARKER = "demo.json"


def demo_studies() -> list[str]:
    """The demo's studies that exist in the studies folders."""
    from drake_mh.study import available_studies

    found = set(available_studies())
    return list(DEMO_STUDIES) + [s for s in OPTIONAL_DEMO_STUDIES if s in found]


@dataclass(frozen=True)
class Earlier:
    """Finished cases found in a demo folder before running.

    Attributes:
        cases: finished cases per study folder.
        created: when the earliest of those studies started ('' if unknown).
    """

    cases: dict[str, int]
    created: str

    @property
    def total(self) -> int:
        """All finished cases found."""
        return sum(self.cases.values())


def earlier_results(out: Path, studies: list[str]) -> Earlier:
    """Counts the finished cases of the demo's studies already in ``out``."""
    from drake_mh.study.store import RecordStore

    cases, created = {}, []
    for name in studies:
        folder = out / name
        if not (folder / "study.json").is_file():
            continue
        store = RecordStore(folder)
        cases[name] = len(store.records())
        created.append(str((store.read_meta() or {}).get("created", "")))
    return Earlier(cases, min((c for c in created if c), default=""))


def _is_demo_folder(folder: Path, studies: list[str]) -> bool:
    return (folder / MARKER).is_file() or any((folder / s / "study.json").is_file() for s in studies)


def move_aside(out: Path, studies: list[str], now: datetime.datetime | None = None) -> Path | None:
    """Moves an earlier demo folder to ``<out>-<YYYYmmdd-HHMMSS>`` (nothing is deleted).

    Returns:
        The new location, or ``None`` when ``out`` does not exist.

    Raises:
        InvalidArgument: ``out`` exists but is not a demo results folder.
    """
    if not out.exists():
        return None
    if not out.is_dir() or not _is_demo_folder(out, studies):
        raise InvalidArgument(f"{out} exists but is not a demo results folder; choose another --out")
    stamp = (now or datetime.datetime.now()).strftime("%Y%m%d-%H%M%S")
    target = out.with_name(f"{out.name}-{stamp}")
    suffix = 1
    while target.exists():
        target = out.with_name(f"{out.name}-{stamp}-{suffix}")
        suffix += 1
    out.rename(target)
    return target


def reuse_message(out: Path, earlier: Earlier) -> str:
    """One sentence telling that earlier results are reused and how to start afresh."""
    per_study = ", ".join(f"{name} {n}" for name, n in earlier.cases.items())
    since = f" (first started {earlier.created})" if earlier.created else ""
    return (f"Reusing {earlier.total} finished cases from an earlier run in {out}{since}: {per_study}. "
            f"They are not run again; `drake-mh demo --fresh` runs everything anew (the earlier results "
            f"are moved to {out.name}-<date>-<time>, not deleted).")


def key_figures(folder: Path, study: str) -> list:
    """The study report's key blocks for the demo page: the reasons of success rates below
    100 % (a small table, when there are any) and its key figures (:data:`KEY_FIGURES`, at
    most two)."""
    from drake_mh.study.report import ReportData, build_document
    from drake_mh.study.report.plots import FigureFile
    from drake_mh.study.report.tables import Table, method_table

    try:
        data = ReportData.load(folder)
        doc = build_document(data)
    except Exception as exc:  # a figure must not sink the demo page
        logger.warning("no figures from %s: %s", folder, exc)
        return []
    blocks: list = []
    table = method_table(data)
    if table.headers[-1] == "why not 100 %":
        names = len(data.group_keys) + 1  # group columns and the method
        rate = table.headers.index("success [%]")
        rows, group = [], []
        for row in table.rows:
            group = row[:names - 1] if any(row[:names - 1]) else group  # the table names a group once
            if row[-1]:
                rows.append(group + row[names - 1:names] + [row[rate], row[-1]])
        caption = f"A case succeeds within: {data.fields.conditions.rstrip('.')}." if data.fields.conditions else ""
        blocks.append(Table(table.headers[:names] + ["success [%]", "why not 100 %"], rows, caption))
    figures = {b.name: b for b in doc.blocks if isinstance(b, FigureFile)}
    chosen = [figures[n] for n in KEY_FIGURES if n in figures][:2]
    return blocks + [FigureFile(f"{study}-{f.name}", f.png, f.caption) for f in chosen]


def demo_animation(out: Path) -> object | None:
    """Records :data:`DEMO_ANIMATION` into ``<out>/animation.html``; returns its report block.

    ``None`` when the trajectory or ``drake_mh.viz`` is missing (the page says so instead).
    """
    import numpy as np

    from drake_mh.study.report.document import Animation
    from drake_mh.study.store import RecordStore

    study, robot_name, prefix, title = DEMO_ANIMATION
    folder = out / study
    if not (folder / "records.jsonl").is_file():
        return None
    store = RecordStore(folder)
    for record in store.records():
        if record.get("status") != "ok" or not str(record.get("method", "")).startswith(prefix):
            continue
        arrays = store.load_arrays(record) if record.get("arrays") else {}
        if "traj_t" not in arrays or "traj_q" not in arrays:
            continue
        try:
            import drake_mh
            from drake_mh.viz import animation_html
        except ImportError as exc:
            logger.info("no demo animation: %s", exc)
            return None
        robot = drake_mh.load_robot(robot_name)
        page = animation_html(robot, (np.asarray(arrays["traj_t"]), np.asarray(arrays["traj_q"])))
        (out / "animation.html").write_text(page, encoding="utf-8")
        return Animation("animation.html", f"{title} ({record.get('key')})", page)
    return None


def mark_folder(out: Path, studies: list[str]) -> None:
    """Creates the demo folder ``out`` and its :data:`MARKER` (what tells ``--fresh`` the folder is the demo's)."""
    from drake_mh.study.store import write_atomic

    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / MARKER, json.dumps({"studies": studies}).encode("utf-8"))


def study_section(out: Path, name: str, result) -> list:
    """The demo page's section of one study: its summary, key figures (:func:`key_figures`), the
    count of its cases (run now, reused, raised) and a link to its own report.

    Args:
        out: the demo folder (the study's results are in ``out / name``).
        name: the study.
        result: its :class:`~drake_mh.study.runner.StudyResult`.
    """
    from drake_mh.study.report.document import Heading, Link, Markdown, Paragraph

    section = [Heading(name)]
    if result.summary.strip():
        section.append(Markdown(result.summary))
    section += key_figures(out / name, name)
    line = f"{len(result.records)}/{result.n_cases} cases"
    line += f" ({result.n_new} run now, {len(result.records) - result.n_new} reused from the earlier run)" \
        if len(result.records) > result.n_new else ""
    line += f", {result.n_errors} raised" if result.n_errors else ""
    return section + [Paragraph(line + "."), Link(f"{name}/index.html", f"{name}: full report (tables, statistics, figures)")]


def write_page(out: Path, sections: list[list], results: list, elapsed: float) -> Path:
    """Writes the demo page: ``out/index.html``, ``out/report.md`` and ``out/figures/``: an
    introduction, the count of reused cases, the 3-D animation (:func:`demo_animation`), then
    the studies' ``sections`` (:func:`study_section`) and the wall time ``elapsed`` [s].

    Returns:
        The path of ``index.html``.
    """
    from drake_mh.study.report.document import Document, Heading, Paragraph, to_html, to_markdown
    from drake_mh.study.store import write_atomic

    doc = Document(title="drake_mh demo")
    doc.add(Paragraph(
        "Quick forms of the demo studies, run end to end on the bundled robots: batched kinematics "
        "against Drake, its accuracy, time-optimal retiming and inverse kinematics. Each section shows "
        "the study's summary and key figures; its full report is linked below it."))
    reused = sum(len(r.records) - r.n_new for r in results)
    if reused:
        doc.add(Paragraph(f"**Reused results:** {reused} of {sum(len(r.records) for r in results)} cases come "
                          f"from an earlier run in this folder and were not run again; run `drake-mh demo --fresh` "
                          "to recompute everything (the earlier results are moved aside, not deleted)."))
    animation = demo_animation(out)
    if animation is not None:
        doc.add(Heading("A motion in 3-D"))
        doc.add(animation)
    for section in sections:
        for block in section:
            doc.add(block)
    doc.add(Paragraph(f"Demo wall time {elapsed:.1f} s."))
    for block in doc.blocks:
        if hasattr(block, "png"):
            write_atomic(out / "figures" / f"{block.name}.png", block.png)
    write_atomic(out / "report.md", to_markdown(doc).encode("utf-8"))
    write_atomic(out / "index.html", to_html(doc).encode("utf-8"))
    return out / "index.html"
