"""Per-method summary table (one row per group × method) and the list of failed cases."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from drake_mh.study.report.data import ReportData, as_float, is_success
from drake_mh.study.report.units import time_unit, with_unit


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
    if digits <= 4 and 1e3 <= abs(value) < 1e6:
        return f"{value:,.0f}"  # 3,040 rather than 3.04e+03
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
    """Returns (median, q25, q75, p95) of ``values`` (NaN when empty)."""
    if values.size == 0:
        return (math.nan,) * 4
    q25, median, q75, p95 = np.percentile(values, [25, 50, 75, 95])
    return float(median), float(q25), float(q75), float(p95)


def failure_note(data: ReportData, records: list[dict], time_scale: tuple[str, float] | None = None) -> str:
    """Why cases of one row failed: how many, the evaluations and error they ended at, and
    their commonest message (``fields.message``); ``""`` when every case succeeded.

    Args:
        data: the loaded results.
        records: the row's records.
        time_scale: ``(unit, factor)`` of the table's time columns.
    """
    fields = data.fields
    if not any(fields.success in r for r in records):
        return ""
    failed = [r for r in records if not is_success(r, fields)]
    if not failed:
        return ""
    parts = [f"{len(failed)}/{len(records)} failed"]
    raised = [r for r in failed if r.get("status") == "error"]
    if raised:
        kind = Counter(str(r.get("exception_type") or "exception") for r in raised).most_common(1)[0][0]
        parts.append(f"{len(raised)} raised {kind}")
    ran = [r for r in failed if r.get("status") == "ok"]
    nfe = np.array([as_float(r.get(fields.nfe)) for r in ran])
    nfe = nfe[np.isfinite(nfe)]
    if nfe.size:
        most = max(as_float(r.get(fields.nfe)) for r in records if np.isfinite(as_float(r.get(fields.nfe))))
        if np.all(nfe == most) and most > 0:
            parts.append(f"budget spent ({most:,.0f} evaluations each)")
        else:
            parts.append(f"{np.median(nfe):,.0f} evaluations (median)")
    error = np.array([as_float(r.get(fields.error)) for r in ran])
    error = error[np.isfinite(error)]
    if error.size:
        unit = f" {fields.error_unit}" if fields.error_unit else ""
        parts.append(f"{fields.error} {fmt(np.median(error))}{unit} (median)")
    times = np.array([as_float(r.get(fields.time)) for r in ran])
    times = times[np.isfinite(times)]
    if times.size and time_scale is not None and not nfe.size:
        unit, factor = time_scale
        parts.append(f"time {fmt(np.median(times) * factor)} {unit} (median)")
    messages = Counter(str(r.get(fields.message)).strip() for r in ran if r.get(fields.message))
    if messages:
        text, count = messages.most_common(1)[0]
        parts.append(f"{count}x \"{text[:80]}\"")
    return parts[0] + ": " + "; ".join(parts[1:]) if len(parts) > 1 else parts[0]


def method_table(data: ReportData) -> Table:
    """Per-method table: cases, exceptions, success rate, time / error spread, evaluations.

    One row per method, or per (group, method) when the study declares ``fields.group_by``
    (instances of a different kind are never pooled; the group's values are written on its
    first row only). Every header states its unit; times
    are shown in the unit (s, ms, µs) that suits the column. Rows with failures get a note
    saying why (see :func:`failure_note`). Time, error and evaluation statistics are over
    the cases that did not raise; the success rate is over all cases (a case that raised
    counts as a failure).
    """
    fields = data.fields
    has_success = any(fields.success in r for r in data.records)
    has_time = data.has_field(fields.time)
    has_error = data.has_field(fields.error)
    has_nfe = data.has_field(fields.nfe)
    time_scale = time_unit(data.values(data.records, fields.time)) if has_time else None
    group_keys = list(data.group_keys)
    headers = group_keys + ["method", "cases", "raised"]
    if has_success:
        headers.append("success [%]")
    if has_time:
        unit = time_scale[0]
        headers += [with_unit(f"{fields.time} {s}", unit) for s in ("median", "IQR", "p95")]
    if has_error:
        headers += [with_unit(f"{fields.error} {s}", fields.error_unit) for s in ("median", "IQR", "p95")]
    if has_nfe:
        headers += [f"{fields.nfe} median [count]", f"{fields.nfe} mean [count]"]
    rows, notes = [], []
    for group, group_records in data.by_group().items():
        for index, (method, records) in enumerate(data.by_method(group_records).items()):
            n = len(records)
            raised = sum(1 for r in records if r.get("status") == "error")
            # the group's values on its first row only: the eye finds where a group starts
            row = [str(v) if index == 0 else "" for v in group] + [method, str(n), str(raised)]
            if has_success:
                rate = sum(1 for r in records if is_success(r, fields)) / n if n else math.nan
                row.append(f"{100 * rate:.1f}")
            if has_time:
                median, q25, q75, p95 = (v * time_scale[1] for v in _spread(data.values(records, fields.time)))
                row += [fmt(median), fmt(q75 - q25), fmt(p95)]
            if has_error:
                median, q25, q75, p95 = _spread(data.values(records, fields.error))
                row += [fmt(median), fmt(q75 - q25), fmt(p95)]
            if has_nfe:
                nfe = data.values(records, fields.nfe)
                row += [fmt(np.median(nfe) if nfe.size else math.nan, 6), fmt(nfe.mean() if nfe.size else math.nan, 6)]
            rows.append(row)
            notes.append(failure_note(data, records, time_scale))
    if any(notes):
        headers.append("why not 100 %")
        for row, note in zip(rows, notes):
            row.append(note)
    caption = (
        "Success rate over all cases (a case that raised counts as a failure); time, error and "
        "function-evaluation statistics over the cases that did not raise. IQR = q75 - q25."
    )
    if group_keys:
        caption += f" One row per {' x '.join(group_keys)} and method: instances of a different kind are not pooled."
    if fields.conditions:
        caption += f" A case succeeds within: {fields.conditions.rstrip('.')}."
    elif any(notes):
        caption += " Budget and tolerance: see the study's description."
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
