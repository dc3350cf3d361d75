"""Reading a results folder into what the report needs: metadata, records, fields, metrics."""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from drake_mh.study.spec import Fields
from drake_mh.study.store import RecordStore

logger = logging.getLogger(__name__)


def as_float(value: Any) -> float:
    """Returns ``value`` as a float, NaN for anything non-numeric (None, str, missing)."""
    if isinstance(value, bool):
        return float(value)
    if isinstance(value, (int, float)):
        return float(value)
    return math.nan


def is_success(record: dict[str, Any], fields: Fields) -> bool:
    """A case succeeded when it did not raise and its success field is true."""
    return record.get("status") == "ok" and bool(record.get(fields.success, False))


@dataclass
class ReportData:
    """Everything loaded from a results folder.

    Attributes:
        folder: results folder.
        meta: ``study.json`` contents (``{}`` if missing).
        records: records in grid order where known.
        fields: report fields.
        methods: method names in order of first appearance.
        instance_keys: keys that define paired blocks.
        summary: the study's ``summary.md`` text ('' if none).
        outside_grid: records left out because their key is not a case of the study's grid.
    """

    folder: Path
    meta: dict[str, Any]
    records: list[dict[str, Any]]
    fields: Fields
    methods: list[str]
    instance_keys: tuple[str, ...]
    summary: str = ""
    store: RecordStore = field(repr=False, default=None)
    outside_grid: int = 0

    @classmethod
    def load(cls, folder: str | os.PathLike) -> ReportData:
        """Loads a results folder.

        Raises:
            NoResults: no ``records.jsonl`` in the folder.
        """
        store = RecordStore(folder)
        records = store.records()
        meta = store.read_meta() or {}
        outside = 0
        if meta.get("case_keys"):  # records of another grid (an edited study, copied lines) are not this study's
            keys = set(meta["case_keys"])
            kept = [r for r in records if r.get("key") in keys]
            outside = len(records) - len(kept)
            records = kept
        fields = _with_declared_layout(Fields.from_dict(meta.get("fields", {})), meta)
        records.sort(key=lambda r: r.get("key", ""))
        grid_keys = meta.get("grid_keys") or []
        if fields.instance is not None:
            instance_keys = tuple(fields.instance)
        elif meta.get("instance_keys") is not None:
            instance_keys = tuple(meta["instance_keys"])
        else:
            instance_keys = tuple(k for k in grid_keys if k != fields.method)
        methods: list[str] = [m for m in meta.get("methods", []) if any(method_of(r, fields) == m for r in records)]
        for record in records:
            name = method_of(record, fields)
            if name not in methods:
                methods.append(name)
        summary_path = Path(folder) / "summary.md"
        summary = summary_path.read_text(encoding="utf-8") if summary_path.is_file() else ""
        return cls(
            folder=Path(folder),
            meta=meta,
            records=records,
            fields=fields,
            methods=methods,
            instance_keys=instance_keys,
            summary=summary,
            store=store,
            outside_grid=outside,
        )

    @property
    def name(self) -> str:
        """Study name (folder name if unknown)."""
        return self.meta.get("name") or self.folder.name

    def by_method(self, records: list[dict[str, Any]] | None = None) -> dict[str, list[dict[str, Any]]]:
        """Groups records (default all) by method, in the order of :attr:`methods`; methods
        without a record in ``records`` are left out unless ``records`` is ``None``."""
        groups: dict[str, list[dict[str, Any]]] = {m: [] for m in self.methods}
        for record in self.records if records is None else records:
            groups[method_of(record, self.fields)].append(record)
        if records is not None:
            groups = {m: g for m, g in groups.items() if g}
        return groups

    @property
    def group_keys(self) -> tuple[str, ...]:
        """The fields that split the records into groups of a different kind (``fields.group_by``)."""
        return tuple(self.fields.group_by or ())

    def by_group(self) -> dict[tuple, list[dict[str, Any]]]:
        """Groups records by the values of :attr:`group_keys` (one group ``()`` when none).

        Groups are ordered by value: numbers numerically, other values in order of first
        appearance.
        """
        keys = self.group_keys
        groups: dict[tuple, list[dict[str, Any]]] = {}
        for record in self.records:
            groups.setdefault(tuple(record.get(k) for k in keys), []).append(record)
        first = {g: i for i, g in enumerate(groups)}

        def order(group: tuple) -> list:
            return [(0, float(v), 0) if isinstance(v, (int, float)) and not isinstance(v, bool)
                    else (1, 0.0, first[group]) for v in group]

        return {g: groups[g] for g in sorted(groups, key=order)}

    def group_label(self, group: tuple) -> str:
        """``"N = 128"``, ``"function = F5, dim = 10"``; ``""`` for the single group ``()``."""
        return ", ".join(f"{k} = {v}" for k, v in zip(self.group_keys, group))

    def values(self, records: list[dict[str, Any]], name: str, ok_only: bool = True) -> np.ndarray:
        """Returns the finite values of field ``name`` as a ``(n,)`` float array."""
        out = [as_float(r.get(name)) for r in records if (r.get("status") == "ok" or not ok_only)]
        array = np.asarray(out, dtype=float)
        return array[np.isfinite(array)]

    def has_field(self, name: str) -> bool:
        """True when some successful-run record has a numeric value for ``name``."""
        return any(
            r.get("status") == "ok" and isinstance(r.get(name), (int, float)) for r in self.records
        )

    def errors(self) -> list[dict[str, Any]]:
        """Records of cases that raised."""
        return [r for r in self.records if r.get("status") == "error"]


#: Fields entries added after results may have been written; taken from the study file when missing
_LAYOUT_FIELDS = ("group_by", "error_unit", "conditions")


def _with_declared_layout(fields: Fields, meta: dict[str, Any]) -> Fields:
    """Fills report-layout fields that ``study.json`` predates (written before ``group_by``,
    ``error_unit`` and ``conditions`` existed) from the study file it names, so that
    ``drake-mh report`` on earlier results groups and labels like a new run. Any problem
    loading the study leaves the fields as they are."""
    stored = meta.get("fields") or {}
    source = meta.get("source")
    if not source or all(k in stored for k in _LAYOUT_FIELDS) or not Path(source).is_file():
        return fields
    try:
        from drake_mh.study.loader import load_study

        declared = load_study(source)[0].fields
    except Exception as exc:  # an old or moved study file must not stop the report
        logger.info("report layout of %s not read: %s", source, exc)
        return fields
    if declared.method != fields.method:
        return fields
    return replace(fields, **{k: getattr(declared, k) for k in _LAYOUT_FIELDS if k not in stored})


def method_of(record: dict[str, Any], fields: Fields) -> str:
    """The record's method name (``"(all)"`` when the study has no method field)."""
    value = record.get(fields.method)
    return "(all)" if value is None else str(value)
