"""Per-method summary table and the list of failed cases."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_mh.study.report.data import ReportData, is_success


def fmt(value: float, digits: int = 3) -> str:
    """Formats a number compactly (``'-'`` for NaN/None)."""
    if value is None:
        return "-"
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(int(value))
    value = float(value)
    if math.isnan(value):
        return "-"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}g}"


@dataclass(frozen=True)
class Table:
    """A table ready for markdown or HTML.

    Attributes:
        headers: column titles.
        rows: cells as text.
        caption: one sentence under the table.
    """

    headers: list[str]
    rows: list[list[str]]
    caption: str = ""


def _spread(values: np.ndarray) -> tuple[float, float, float, float]:
    """Median, IQR (q75 - q25), 25th percentile... returns (median, q25, q75, p95)."""
    if values.size == 0:
        return (math.nan,) * 4
    q25, median, q75, p95 = np.percentile(values, [25, 50, 75, 95])
    return float(median), float(q25), float(q75), float(p95)


def method_table(data: ReportData) -> Table:
    """Per-method table: cases, exceptions, success rate, time / error spread, nfe.

    Time, error and nfe statistics are over the cases that did not raise; the success rate
    is over all cases (a case that raised counts as a failure).
    """
    fields = data.fields
    has_success = any(fields.success in r for r in data.records)
    has_time = data.has_field(fields.time)
    has_error = data.has_field(fields.error)
    has_nfe = data.has_field(fields.nfe)
    headers = ["method", "cases", "raised"]
    if has_success:
        headers.append("success")
    if has_time:
        headers += [f"{fields.time} median", f"{fields.time} IQR", f"{fields.time} p95"]
    if has_error:
        headers += [f"{fields.error} median", f"{fields.error} IQR", f"{fields.error} p95"]
    if has_nfe:
        headers += [f"{fields.nfe} median", f"{fields.nfe} mean"]
    rows = []
    for method, records in data.by_method().items():
        n = len(records)
        raised = sum(1 for r in records if r.get("status") == "error")
        row = [method, str(n), str(raised)]
        if has_success:
            rate = sum(1 for r in records if is_success(r, fields)) / n if n else math.nan
            row.append(f"{100 * rate:.1f} %")
        if has_time:
            median, q25, q75, p95 = _spread(data.values(records, fields.time))
            row += [fmt(median), fmt(q75 - q25), fmt(p95)]
        if has_error:
            median, q25, q75, p95 = _spread(data.values(records, fields.error))
            row += [fmt(median), fmt(q75 - q25), fmt(p95)]
        if has_nfe:
            nfe = data.values(records, fields.nfe)
            row += [fmt(np.median(nfe) if nfe.size else math.nan, 6), fmt(nfe.mean() if nfe.size else math.nan, 6)]
        rows.append(row)
    caption = (
        "Success rate over all cases (a case that raised counts as a failure); time, error and "
        "function-evaluation statistics over the cases that did not raise. IQR = q75 - q25."
    )
    return Table(headers, rows, caption)


def failures_table(data: ReportData, limit: int = 50) -> Table | None:
    """Cases that raised: key, exception type and message (first ``limit``)."""
    errors = data.errors()
    if not errors:
        return None
    rows = [
        [str(r.get("key")), str(r.get("exception_type", "")), str(r.get("exception", "")).splitlines()[0][:200] if r.get("exception") else ""]
        for r in errors[:limit]
    ]
    more = len(errors) - len(rows)
    caption = f"{len(errors)} case(s) raised" + (f"; the first {limit} are listed" if more > 0 else "") + "; full tracebacks are in records.jsonl."
    return Table(["case", "exception", "message"], rows, caption)
