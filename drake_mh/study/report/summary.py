"""Building blocks of a study's own summary (``Study.summarize``): finished records, robust
statistics that skip missing values, grouping, markdown tables, rank tables, the CPU and its load.

A study script declares its grid and its ``run`` function and writes its summary from these
helpers, so that every study computes a median, a p95, a ratio or a rank test the same way.
Statistics follow :mod:`drake_mh.study.report.stats` (Friedman ranks, Wilcoxon-Holm against the
best; Derrac et al. 2011).

Example::

    ok = finished(records)
    rows = [[m, cell(median(values(g, "time", 1e3)), ".2f"), cell(p95(values(g, "time", 1e3)), ".2f")]
            for m, g in group_by(ok, "method").items()]
    return "\\n".join([cpu_and_load(ok), ""] + markdown_table(["method", "median [ms]", "p95 [ms]"], rows))
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from drake_mh.study.report.data import as_float

__all__ = [
    "finished", "values", "median", "p95", "percentile", "quartiles", "median_iqr", "mean", "ratio",
    "share", "cell", "group_by", "markdown_table", "load_range", "cpu_and_load", "rank_lines",
]


def finished(records: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """The records of cases that did not raise (``status == "ok"``), in their order."""
    return [r for r in records if r.get("status") == "ok"]


def values(records: Iterable[dict[str, Any]], key: str, scale: float = 1.0) -> np.ndarray:
    """The finite values of field ``key`` times ``scale`` as a ``(n,)`` float array (records
    without the field, or with a non-numeric or NaN value, are skipped)."""
    out = np.array([as_float(r.get(key)) for r in records], dtype=float) * scale
    return out[np.isfinite(out)]


def _finite(data: Iterable[float]) -> np.ndarray:
    array = np.asarray([as_float(v) for v in data], dtype=float)
    return array[~np.isnan(array)]


def percentile(data: Iterable[float], q: float) -> float:
    """The ``q``-th percentile of ``data`` (NaN entries skipped; NaN when nothing is left)."""
    array = _finite(data)
    return float(np.percentile(array, q)) if array.size else math.nan


def median(data: Iterable[float]) -> float:
    """The median of ``data`` (NaN entries skipped; NaN when nothing is left)."""
    return percentile(data, 50)


def p95(data: Iterable[float]) -> float:
    """The 95th percentile of ``data`` (NaN entries skipped; NaN when nothing is left)."""
    return percentile(data, 95)


def mean(data: Iterable[float]) -> float:
    """The mean of ``data`` (NaN entries skipped; NaN when nothing is left)."""
    array = _finite(data)
    return float(array.mean()) if array.size else math.nan


def quartiles(data: Iterable[float]) -> tuple[float, float, float]:
    """``(q25, median, q75)`` of ``data`` (NaN entries skipped; NaNs when nothing is left)."""
    array = _finite(data)
    if not array.size:
        return (math.nan,) * 3
    q25, q50, q75 = np.percentile(array, [25, 50, 75])
    return float(q25), float(q50), float(q75)


def median_iqr(data: Iterable[float], spec: str = ".3g", spread_spec: str | None = None) -> str:
    """``"median [q25, q75]"`` with the median formatted by ``spec`` and the quartiles by
    ``spread_spec`` (default ``spec``); ``"-"`` when there is no value."""
    q25, q50, q75 = quartiles(data)
    if math.isnan(q50):
        return "-"
    spread_spec = spread_spec or spec
    return f"{q50:{spec}} [{q25:{spread_spec}}, {q75:{spread_spec}}]"


def ratio(numerator: float, denominator: float) -> float:
    """``numerator / denominator``; NaN when either is NaN or the denominator is 0."""
    numerator, denominator = as_float(numerator), as_float(denominator)
    if math.isnan(numerator) or math.isnan(denominator) or denominator == 0:
        return math.nan
    return numerator / denominator


def share(records: Sequence[dict[str, Any]], key: str = "success") -> float:
    """The fraction of ``records`` whose field ``key`` is true (a missing field counts as
    false); NaN for no record."""
    return sum(bool(r.get(key)) for r in records) / len(records) if records else math.nan


def cell(value: Any, spec: str = ".3g", missing: str = "-") -> str:
    """``value`` formatted by ``spec``; ``missing`` for None and NaN (a table cell)."""
    number = as_float(value)
    if value is None or math.isnan(number):
        return missing
    return f"{value:{spec}}"


def group_by(records: Iterable[dict[str, Any]], *keys: str) -> dict[Any, list[dict[str, Any]]]:
    """Records grouped by the value of one field (the value is the group's key) or of several
    (a tuple), groups in order of first appearance."""
    groups: dict[Any, list[dict[str, Any]]] = {}
    for record in records:
        key = record.get(keys[0]) if len(keys) == 1 else tuple(record.get(k) for k in keys)
        groups.setdefault(key, []).append(record)
    return groups


def markdown_table(headers: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """A markdown pipe table as lines: the header, its separator and one line per row (cells
    written with ``str``)."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def load_range(records: Iterable[dict[str, Any]], *keys: str) -> tuple[float, float]:
    """Smallest and largest finite value of the load-average fields ``keys`` over ``records``
    (NaN, NaN when none)."""
    records = list(records)
    loads = np.concatenate([values(records, k) for k in keys]) if keys else np.array([])
    return (float(loads.min()), float(loads.max())) if loads.size else (math.nan, math.nan)


def cpu_and_load(records: Sequence[dict[str, Any]], cpu: str = "cpu", loads: Sequence[str] = ("load_average",),
                 digits: int = 1) -> str:
    """``"CPU: <model> (<n> logical CPUs); 1-minute load average <lo>-<hi> during the cases"``
    from the records' ``cpu`` field and the range of their ``loads`` fields, which a study
    measures beside its own timings (:func:`drake_mh.study.machine.cpu_model`, ``load_average``);
    :func:`drake_mh.study.machine.machine_line` reads the runner's fields around whole cases."""
    model = next((r[cpu] for r in records if r.get(cpu)), "?")
    lo, hi = load_range(records, *loads)
    return (f"CPU: {model} ({os.cpu_count()} logical CPUs); 1-minute load average "
            f"{lo:.{digits}f}-{hi:.{digits}f} during the cases")


def rank_lines(records: list[dict[str, Any]], methods: Sequence[str], metric: str, instance_keys: Sequence[str],
               label: str, method_key: str = "method", lower_is_better: bool = True) -> list[str]:
    """Friedman average ranks of ``metric`` over the blocks ``instance_keys`` and Wilcoxon
    signed-rank tests of the best method against each other, Holm-corrected
    (:func:`drake_mh.study.report.stats.rank_stats`), as a sentence and a markdown table. A
    record that raised or has no value ranks last in its block.

    Args:
        records: the study's records.
        methods: the methods to rank, in the order ties are listed.
        metric: the ranked field.
        instance_keys: the fields whose values make one block (paired comparison).
        label: what is ranked, starts the sentence.
        method_key: the field naming the method.
        lower_is_better: orientation of ``metric``.
    """
    from drake_mh.study.report.data import ReportData
    from drake_mh.study.report.stats import rank_stats
    from drake_mh.study.spec import Fields

    present = [m for m in methods if any(r.get(method_key) == m for r in records)]
    data = ReportData(folder=Path("."), meta={}, records=list(records),
                      fields=Fields(method=method_key, error=metric, lower_is_better=lower_is_better),
                      methods=present, instance_keys=tuple(instance_keys))
    stats = rank_stats(data, metric)
    if stats is None:
        return [f"{label}: needs two methods and one block where every method ran."]
    friedman = (f"Friedman chi2 = {stats.friedman_statistic:.1f}, p = {stats.friedman_p:.1e}"
                if stats.friedman_statistic == stats.friedman_statistic else "Friedman: needs 3 methods and 2 blocks")
    tests = {t.method: t for t in stats.pairwise}
    rows = [[m, f"{rank:.2f}", "(best)" if m not in tests else f"{tests[m].wins}/{tests[m].losses}/{tests[m].ties}",
             "" if m not in tests else f"{tests[m].p_holm:.1e}"] for m, rank in zip(stats.methods, stats.average_ranks)]
    head = (f"{label}: {stats.n_blocks} blocks ({' x '.join(instance_keys)}), a failure ranks last; {friedman}; "
            f"Wilcoxon signed-rank of {stats.best} against each, Holm-corrected.")
    return [head, ""] + markdown_table(["method", "mean rank", f"{stats.best} wins/losses/ties", "p (Holm)"], rows)
