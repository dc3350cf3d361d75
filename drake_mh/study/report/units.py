"""Units in report headers and axes: times shown in s, ms or µs, every header with its unit."""

from __future__ import annotations

import numpy as np

#: display units of a time in seconds, largest first: (unit, factor from s)
TIME_UNITS: tuple[tuple[str, float], ...] = (("s", 1.0), ("ms", 1e3), ("µs", 1e6))


def time_unit(values_s) -> tuple[str, float]:
    """The display unit of times ``values_s`` [s]: the largest unit in which their median is >= 1.

    Args:
        values_s: times [s] (any shape; NaN ignored).

    Returns:
        ``(unit, factor)``: show ``value_s * factor`` with header ``[unit]``; ``("s", 1.0)``
        when there is no finite value.
    """
    values = np.abs(np.asarray(values_s, dtype=float).ravel())
    values = values[np.isfinite(values) & (values > 0)]
    if values.size == 0:
        return TIME_UNITS[0]
    median = float(np.median(values))
    for unit, factor in TIME_UNITS:
        if median * factor >= 1.0:
            return unit, factor
    return TIME_UNITS[-1]


def with_unit(label: str, unit: str | None) -> str:
    """``"time median [ms]"``; ``"[-]"`` for a dimensionless quantity (``unit == ""``); the
    label alone when the unit is unknown (``None``)."""
    if unit is None:
        return label
    return f"{label} [{unit or '-'}]"
