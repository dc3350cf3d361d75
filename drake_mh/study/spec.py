"""Declaration of a study: :class:`Study`, :class:`Fields` and grid expansion."""

from __future__ import annotations

import inspect
import itertools
import logging
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Union

from drake_mh.errors import InvalidStudy

if TYPE_CHECKING:  # pragma: no cover
    from drake_mh.study.case import Case

logger = logging.getLogger(__name__)

Grid = Union[Mapping[str, Sequence[Any]], Sequence[Mapping[str, Any]]]
_SCALARS = (str, int, float, bool)


@dataclass(frozen=True)
class Fields:
    """Which record fields the report reads.

    Attributes:
        method: field naming the method (one table row / curve per value).
        success: boolean success field.
        time: solve time [s] (measured by the case, not the runner's ``wall_time``).
        error: the error metric that statistics rank (e.g. final position error [m]).
        nfe: number of function evaluations used.
        instance: fields identifying a block (problem instance × replicate) for paired
            statistics; ``None`` means every grid key except ``method``.
        lower_is_better: orientation of ``error``.
        rank: whether the method values are competing methods to rank (Friedman / Wilcoxon);
            ``False`` e.g. when the "method" field is a robot in a verification study.
        panels: fields whose value combinations each get their own convergence panel (e.g.
            ``("function", "dim", "shift")``: problems of different scale are not pooled);
            ``None``: :attr:`group_by` if given, else the first instance field when it has 2-6
            values, else one panel.
        group_by: fields whose values are instances of a different kind (another component,
            another N, another test function): the report's per-method table gets one row per
            (group, method) and the box plots one panel per group, so that numbers of
            different scale are never pooled into one median; ``None``: one row per method.
        error_unit: unit of ``error`` shown in column headers and axis labels (e.g. ``"m"``,
            ``"rad"``); ``""`` when it has none (a fitness), ``None`` when unknown.
        message: field holding a case's own message (e.g. ``IKResult.message``); the report
            shows the commonest one of the failed cases next to a success rate below 100 %.
        conditions: one sentence stating the budget and tolerance a case succeeds within
            (e.g. ``"20,000 evaluations or 0.5 s per solve; success = 1 mm and 0.01 rad"``),
            shown with the success rates so that a low rate comes with its reason.
    """

    method: str = "method"
    success: str = "success"
    time: str = "time"
    error: str = "error"
    nfe: str = "nfe"
    instance: tuple[str, ...] | None = None
    lower_is_better: bool = True
    rank: bool = True
    panels: tuple[str, ...] | None = None
    group_by: tuple[str, ...] | None = None
    error_unit: str | None = None
    message: str = "message"
    conditions: str = ""

    def to_dict(self) -> dict:
        """Returns the fields as a JSON-friendly dict."""
        return {
            "method": self.method,
            "success": self.success,
            "time": self.time,
            "error": self.error,
            "nfe": self.nfe,
            "instance": None if self.instance is None else list(self.instance),
            "lower_is_better": self.lower_is_better,
            "rank": self.rank,
            "panels": None if self.panels is None else list(self.panels),
            "group_by": None if self.group_by is None else list(self.group_by),
            "error_unit": self.error_unit,
            "message": self.message,
            "conditions": self.conditions,
        }

    @classmethod
    def from_dict(cls, data: Mapping) -> Fields:
        """Inverse of :meth:`to_dict` (unknown keys ignored)."""
        names = ("method", "success", "time", "error", "nfe", "lower_is_better", "rank", "error_unit", "message",
                 "conditions")
        kwargs = {k: data[k] for k in names if k in data}
        for key in ("instance", "panels", "group_by"):
            if data.get(key) is not None:
                kwargs[key] = tuple(data[key])
        return cls(**kwargs)


@dataclass(frozen=True)
class Study:
    """A named grid of cases and the function that runs one case.

    See ``docs/studies.md`` for the full contract.

    Attributes:
        name: identifier (default output folder ``results/<name>``).
        run: ``run(case: Case) -> Mapping`` returning a flat record; module-level function.
        grid: ``{key: values}`` (Cartesian product, key order kept) or a sequence of dicts.
        quick_grid: the same for ``--quick``; defaults to ``grid``.
        seed: study seed from which every case seed is derived.
        fields: record fields the report reads.
        description: one paragraph shown at the top of the report.
        summarize: optional ``summarize(records) -> markdown str``.
        max_workers: cap on concurrent cases (``1`` for timing benchmarks).
    """

    name: str
    run: Callable[[Case], Mapping[str, Any]]
    grid: Grid
    quick_grid: Grid | None = None
    seed: int = 0
    fields: Fields = field(default_factory=Fields)
    description: str = ""
    summarize: Callable[[list[dict]], str] | None = None
    max_workers: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or "/" in self.name:
            raise InvalidStudy(f"study name must be a non-empty string without '/', got {self.name!r}")
        if not callable(self.run):
            raise InvalidStudy(f"study {self.name!r}: run must be a function run(case) -> dict")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InvalidStudy(f"study {self.name!r}: seed must be a non-negative int, got {self.seed!r}")
        if self.max_workers is not None and (not isinstance(self.max_workers, int) or self.max_workers < 1):
            raise InvalidStudy(f"study {self.name!r}: max_workers must be None or an int >= 1")
        if not isinstance(self.fields, Fields):
            raise InvalidStudy(f"study {self.name!r}: fields must be a drake_mh.study.Fields")
        # expand once to validate both grids early (clear message at import time)
        self.cases(quick=False)
        self.cases(quick=True)

    def cases(self, quick: bool = False) -> list[dict[str, Any]]:
        """Expands the (quick) grid into the list of case parameter dicts, in grid order.

        Raises:
            InvalidStudy: the grid is empty, has non-scalar values, unequal keys or duplicates.
        """
        grid = self.quick_grid if (quick and self.quick_grid is not None) else self.grid
        return expand_grid(grid, where=f"study {self.name!r} {'quick_grid' if quick else 'grid'}")

    def grid_keys(self, quick: bool = False) -> list[str]:
        """Returns the grid keys in order."""
        cases = self.cases(quick)
        return list(cases[0])

    def instance_keys(self, quick: bool = False) -> tuple[str, ...]:
        """Returns the keys defining a block for paired statistics."""
        if self.fields.instance is not None:
            return tuple(self.fields.instance)
        return tuple(k for k in self.grid_keys(quick) if k != self.fields.method)

    @property
    def source_file(self) -> str | None:
        """Path of the file defining :attr:`run`, if any."""
        try:
            return inspect.getsourcefile(self.run)
        except TypeError:
            return None


def expand_grid(grid: Grid, where: str = "grid") -> list[dict[str, Any]]:
    """Expands a grid declaration into case parameter dicts.

    Args:
        grid: ``{key: values}`` (Cartesian product in key order) or a sequence of dicts.
        where: prefix of error messages.

    Returns:
        A non-empty list of dicts with identical keys and JSON-scalar values.

    Raises:
        InvalidStudy: on an empty grid, non-scalar values, unequal keys or duplicate cases.
    """
    if isinstance(grid, Mapping):
        keys = list(grid)
        if not keys:
            raise InvalidStudy(f"{where} is empty: give at least one key with values")
        value_lists = []
        for key in keys:
            values = grid[key]
            if isinstance(values, (str, bytes)) or not isinstance(values, Iterable):
                raise InvalidStudy(f"{where}: values of {key!r} must be a list/range, got {values!r}")
            value_lists.append(list(values))
        cases = [dict(zip(keys, combo)) for combo in itertools.product(*value_lists)]
    elif isinstance(grid, Sequence) and not isinstance(grid, (str, bytes)):
        cases = [dict(c) if isinstance(c, Mapping) else c for c in grid]
        if any(not isinstance(c, dict) for c in cases):
            raise InvalidStudy(f"{where}: a sequence grid must contain dicts of grid values")
    else:
        raise InvalidStudy(f"{where} must be a dict of value lists or a list of dicts, got {type(grid).__name__}")
    if not cases:
        raise InvalidStudy(f"{where} has no cases (a value list is empty)")
    first_keys = list(cases[0])
    seen = set()
    for case in cases:
        if list(case) != first_keys:
            raise InvalidStudy(f"{where}: every case needs the keys {first_keys} in that order, got {list(case)}")
        for key, value in case.items():
            if hasattr(value, "item") and not isinstance(value, _SCALARS):
                value = value.item()  # numpy scalar
                case[key] = value
            if not isinstance(value, _SCALARS):
                raise InvalidStudy(f"{where}: value {value!r} of {key!r} must be a str, int, float or bool")
        marker = tuple((k, type(v).__name__, v) for k, v in case.items())
        if marker in seen:
            raise InvalidStudy(f"{where}: duplicate case {case}")
        seen.add(marker)
    return cases
