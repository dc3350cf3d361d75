"""Worker side: run one case, never raise, return a picklable :class:`CaseOutcome`.

The task function :func:`run_case_task` is importable by name, so it works with process
pools (spawn) and Dask workers alike.
"""

from __future__ import annotations

import json
import logging
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drake_mh.study.case import Case, CaseSpec
from drake_mh.study.loader import StudySource, load_source
from drake_mh.study.machine import cpu_model, load_average

logger = logging.getLogger(__name__)


@dataclass
class CaseOutcome:
    """The result of one case, sent back to the main process which stores it.

    Attributes:
        spec: the case.
        record: flat record of scalars (runner fields included).
        arrays: ``{name: ndarray}`` to save as ``arrays/<case_id>.npz``.
        attachments: ``{file name: str | bytes}`` to save under ``artifacts/<case_id>/``.
    """

    spec: CaseSpec
    record: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    attachments: dict[str, str | bytes] = field(default_factory=dict)


def _flatten(values: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name, value in values.items():
        full = f"{prefix}{name}"
        if isinstance(value, Mapping):
            out.update(_flatten(value, prefix=f"{full}."))
        else:
            out[full] = value
    return out


def split_result(result: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Splits a case function's result into JSON scalars and arrays.

    Args:
        result: the mapping returned by the case function.

    Returns:
        ``(scalars, arrays)``; numpy scalars become Python scalars, sequences become arrays.

    Raises:
        TypeError: a value is neither a scalar nor array-like, or ``result`` is no mapping.
    """
    if not isinstance(result, Mapping):
        raise TypeError(f"the case function must return a dict, got {type(result).__name__}")
    scalars: dict[str, Any] = {}
    arrays: dict[str, np.ndarray] = {}
    for name, value in _flatten(result).items():
        if value is None or isinstance(value, (bool, int, float, str)):
            scalars[name] = value
        elif isinstance(value, np.generic) and isinstance(value.item(), (bool, int, float, str)):
            scalars[name] = value.item()
        elif isinstance(value, (np.ndarray, list, tuple)):
            array = np.asarray(value)
            if array.dtype == object:
                raise TypeError(f"result {name!r} is not a numeric/text array")
            arrays[name] = array
        else:
            raise TypeError(
                f"result {name!r} has type {type(value).__name__}; return scalars, arrays or "
                "nested dicts of them (save files with case.attach)"
            )
    return scalars, arrays


def run_case_task(source: StudySource, spec: CaseSpec) -> CaseOutcome:
    """Loads the study (cached per process), runs one case and catches any exception.

    Args:
        source: the study file (path and text).
        spec: the case to run.

    Returns:
        The outcome; ``record["status"]`` is ``"ok"`` or ``"error"``.
    """
    record: dict[str, Any] = {}
    arrays: dict[str, np.ndarray] = {}
    case = Case.from_spec(spec)
    load = load_average()
    start, cpu_start = time.perf_counter(), time.process_time()
    try:
        study = load_source(source)
        result = study.run(case)
        scalars, arrays = split_result(result)
        reserved = set(spec.params) | _RUNNER_FIELDS
        clashes = sorted(reserved & set(scalars) - set(spec.params))
        if clashes:
            raise KeyError(f"the case returned runner-reserved fields {clashes}; rename them")
        for name, value in scalars.items():
            if name in spec.params and value != spec.params[name]:
                raise KeyError(f"the case returned {name!r}={value!r} which differs from its grid value")
        json.dumps(scalars)  # anything that cannot be stored fails here, as this case's error
        record.update(scalars)
        record["status"] = "ok"
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - a failing case must not kill the study
        arrays = {}
        record = {
            "status": "error",
            "exception_type": type(exc).__name__,
            "exception": str(exc)[:2000],
            "traceback": "".join(traceback.format_exception(exc))[-4000:],
        }
        logger.debug("case %s raised", spec.key, exc_info=True)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu_start
    full: dict[str, Any] = dict(spec.params)
    full.update(record)
    full.update(
        {
            "key": spec.key,
            "case_id": spec.case_id,
            "seed": spec.seed,
            "wall_time": wall,
            # the machine, beside every timing (shared machines): a worker runs one case at a time
            "case_cpu_time": cpu,
            "case_load_average": max(load, load_average()),
            "case_cpu_model": cpu_model(),
        }
    )
    return CaseOutcome(spec=spec, record=full, arrays=arrays, attachments=dict(case.attachments))


_RUNNER_FIELDS = frozenset(
    {"key", "case_id", "seed", "status", "wall_time", "case_cpu_time", "case_load_average", "case_cpu_model", "arrays",
     "attachments", "exception", "exception_type", "traceback"}
)
