"""Study reports: ``report.md`` and a self-contained ``index.html`` from a results folder.

``write_report(folder)`` reads ``study.json``, ``records.jsonl``, ``arrays/`` and
``artifacts/`` and writes ``report.md``, ``index.html`` and ``figures/*.png``.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

from drake_mh.study.machine import machine_line
from drake_mh.study.report.data import ReportData, method_of
from drake_mh.study.report.document import Animation, Document, Heading, Markdown, Paragraph, to_html, to_markdown
from drake_mh.study.report.plots import FigureFile, box_figure, convergence_figure, trajectory_figure
from drake_mh.study.report.stats import RankStats, rank_stats
from drake_mh.study.report.tables import Table, failures_table, fmt, method_table
from drake_mh.study.store import write_atomic

logger = logging.getLogger(__name__)

__all__ = ["write_report", "build_document", "machine_line", "ReportData", "rank_stats", "method_table"]

#: embedded animations at most (each Meshcat page is ~2 MB); the others are linked
MAX_EMBEDDED_ANIMATIONS = 4
#: attached figures shown per method (per group and method with ``fields.group_by``); plus one animation
ATTACHMENTS_PER_METHOD = 2


def _stats_blocks(stats: RankStats | None, data: ReportData) -> list:
    if stats is None:
        return [Paragraph("Statistics need at least two methods and one block where every method has a case.")]
    direction = "lower" if data.fields.lower_is_better else "higher"
    friedman = (
        f"Friedman test: chi2 = {fmt(stats.friedman_statistic)}, p = {fmt(stats.friedman_p)}."
        if stats.friedman_statistic == stats.friedman_statistic
        else "Friedman test: needs at least 3 methods and 2 blocks."
    )
    intro = Paragraph(
        f"Ranks of '{stats.metric}' ({direction} is better) within each block of "
        f"{' x '.join(data.instance_keys) or 'cases'} ({stats.n_blocks} complete blocks"
        + (f", {stats.n_incomplete} incomplete blocks left out" if stats.n_incomplete else "")
        + "); a case that raised or has no value ranks last. "
        + friedman
        + f" Best average rank: {stats.best}. Wilcoxon signed-rank tests (two-sided) of {stats.best} "
        "against each other method, paired over blocks, Holm-corrected."
    )
    tests = {t.method: t for t in stats.pairwise}
    rows = []
    for method, rank in zip(stats.methods, stats.average_ranks):
        test = tests.get(method)
        if test is None:
            rows.append([method, fmt(rank), "(best)", "", "", ""])
        else:
            rows.append([method, fmt(rank), f"{test.wins}/{test.losses}/{test.ties}", str(test.n_pairs), fmt(test.p_value), fmt(test.p_holm)])
    table = Table(
        ["method", "average rank", f"{stats.best} wins/losses/ties", "pairs", "p (Wilcoxon)", "p (Holm)"],
        rows,
        "Average Friedman rank (1 = best); p < 0.05 after Holm means the difference to the best is significant.",
    )
    return [intro, table]


def _attachment_blocks(data: ReportData) -> list:
    """Attached figures and animations: per method (per group and method when the study
    declares ``fields.group_by``) at most :data:`ATTACHMENTS_PER_METHOD` figures and one
    animation; at most :data:`MAX_EMBEDDED_ANIMATIONS` animations embedded, the others linked."""
    blocks: list = []
    embedded = 0
    counts: dict[tuple, int] = {}
    for record in data.records:
        method = method_of(record, data.fields)
        owner = (tuple(record.get(k) for k in data.group_keys), method)
        for relative in record.get("attachments") or []:
            path = data.folder / relative
            suffix = path.suffix.lower()
            kind = "animation" if suffix in (".html", ".htm", ".svg") else "figure" if suffix == ".png" else None
            if kind is None or not path.is_file():
                continue
            if counts.get((owner, kind), 0) >= (1 if kind == "animation" else ATTACHMENTS_PER_METHOD):
                continue
            title = f"{method}: {record.get('key')} ({path.name})"
            if kind == "figure":
                blocks.append(FigureFile(f"attachment-{record.get('case_id')}-{path.stem}", path.read_bytes(), title))
            else:
                page = None
                if embedded < MAX_EMBEDDED_ANIMATIONS:
                    page = path.read_text(encoding="utf-8", errors="replace")
                    embedded += 1
                blocks.append(Animation(relative, title, page))
            counts[(owner, kind)] = counts.get((owner, kind), 0) + 1
    return blocks


def build_document(data: ReportData) -> Document:
    """Builds the report's blocks from loaded results."""
    meta = data.meta
    doc = Document(title=f"Study {data.name}")
    if meta.get("description"):
        doc.add(Paragraph(meta["description"]))
    n_cases = meta.get("n_cases")
    finished = len(data.records)
    status = f"{finished} of {n_cases} cases finished" if n_cases else f"{finished} cases"
    if data.outside_grid:
        status += f" ({data.outside_grid} records of cases not in this grid left out)"
    damaged = data.store.damaged if data.store is not None else []
    if damaged:
        status += f" ({len(damaged)} damaged records skipped: {damaged[0][0]}, {damaged[0][1]} ...; they run again)"
    doc.add(
        Paragraph(
            f"{status}; {len(data.errors())} raised. Study seed {meta.get('seed', '?')}"
            + (", quick grid" if meta.get("quick") else "")
            + (f"; source {Path(meta['source']).name}" if meta.get("source") else "")
            + (f"; started {meta['created']}" if meta.get("created") else "")
            + "."
        )
    )
    machine = machine_line(data.records)
    if machine:
        doc.add(Paragraph(machine))
    if data.summary.strip():
        doc.add(Heading("Summary"))
        doc.add(Markdown(data.summary))
    doc.add(Heading("Methods"))
    doc.add(method_table(data))
    if data.fields.rank:
        doc.add(Heading("Statistics"))
        for block in _stats_blocks(rank_stats(data), data):
            doc.add(block)
    figures = [f for f in (convergence_figure(data), box_figure(data), trajectory_figure(data)) if f is not None]
    if figures:
        doc.add(Heading("Figures"))
        for figure in figures:
            doc.add(figure)
    attachments = _attachment_blocks(data)
    if attachments:
        doc.add(Heading("Examples"))
        for block in attachments:
            doc.add(block)
    failures = failures_table(data)
    if failures is not None:
        doc.add(Heading("Cases that raised"))
        doc.add(failures)
    return doc


def write_report(folder: str | os.PathLike) -> Path:
    """Writes ``report.md``, ``index.html`` and ``figures/*.png`` into a results folder.

    Args:
        folder: a results folder made by the study runner (complete or partial).

    Returns:
        Path of ``index.html``.

    Raises:
        NoResults: the folder has no ``records.jsonl``.
    """
    data = ReportData.load(folder)
    doc = build_document(data)
    folder = Path(folder)
    for block in doc.blocks:
        if isinstance(block, FigureFile):
            write_atomic(folder / "figures" / f"{block.name}.png", block.png)
    write_atomic(folder / "report.md", to_markdown(doc).encode("utf-8"))
    index = folder / "index.html"
    write_atomic(index, to_html(doc).encode("utf-8"))
    logger.info("report written to %s", index)
    return index
