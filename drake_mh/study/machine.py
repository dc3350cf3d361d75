"""What machine a benchmark ran on: recorded beside every timing (the machines are shared)."""

from __future__ import annotations

import contextlib
import functools
import os
import platform
from pathlib import Path

import numpy as np

__all__ = ["cpu_model", "load_average", "machine_line"]


@functools.cache
def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``, read once per process), else what ``platform`` knows."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def load_average() -> float:
    """The 1-minute load average (NaN where the OS has none)."""
    try:
        return float(os.getloadavg()[0])
    except OSError:
        return float("nan")


def machine_line(records: list[dict]) -> str:
    """Where the cases ran, from the runner's fields (:mod:`drake_mh.study.worker`): CPU models,
    the 1-minute load average range and the median ratio of CPU to wall time of the cases (well
    below 1: the case waited, for the machine or for I/O). Empty for records without them."""
    timed = [r for r in records if r.get("case_cpu_model") is not None]
    if not timed:
        return ""
    models = sorted({str(r["case_cpu_model"]) for r in timed})
    loads = [r["case_load_average"] for r in timed if r.get("case_load_average") == r.get("case_load_average")]
    ratios = [r["case_cpu_time"] / r["wall_time"] for r in timed
              if r.get("case_cpu_time") is not None and (r.get("wall_time") or 0) > 0]
    line = f"Machine: {', '.join(models)}"
    if loads:
        line += f"; 1-minute load average {min(loads):.1f}-{max(loads):.1f} during the cases"
    if ratios:
        line += f"; case CPU time / wall time, median {float(np.median(ratios)):.2f}"
    return line + f" ({len(timed)} of {len(records)} records)."
