"""What machine a benchmark ran on: recorded beside every timing (the machines are shared)."""

from __future__ import annotations

import contextlib
import functools
import os
import platform
from pathlib import Path

import numpy as np

__all__ = ["cpu_model", "interleaved", "load_average", "machine_line", "timed"]


@functools.cache
def cpu_model() -> str:
    """The CPU's model name with its x86 family, model and widest vector extension, e.g.
    ``"AMD EPYC (family 26 model 2, AVX-512)"`` (``/proc/cpuinfo``, read once per process), else
    what ``platform`` knows.

    Virtual machines often show a bare model name ("AMD EPYC") whatever the generation behind
    it, and the same code's timings under the same name differed by a third between two such
    machines (docs/benchmarks.md): the family and model say whether two records ran on the same
    kind.
    """
    with contextlib.suppress(OSError):
        return _describe(Path("/proc/cpuinfo").read_text())
    return platform.processor() or platform.machine()


def _describe(cpuinfo: str) -> str:
    """:func:`cpu_model` from the text of ``/proc/cpuinfo`` (its first processor's lines)."""
    fields: dict[str, str] = {}
    for line in cpuinfo.splitlines():
        if not line.strip():
            if fields:
                break  # the first processor's block only
            continue
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    name = fields.get("model name") or platform.processor() or platform.machine()
    details = []
    if "cpu family" in fields and "model" in fields:
        details.append(f"family {fields['cpu family']} model {fields['model']}")
    flags = set(fields.get("flags", "").split())
    vector = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "AVX" if "avx" in flags else ""
    if vector:
        details.append(vector)
    return f"{name} ({', '.join(details)})" if details else name


def timed(function, rounds: int = 1) -> tuple[float, float]:
    """Median wall and CPU (process) seconds of ``function()`` over ``rounds`` calls."""
    import time

    wall, cpu = [], []
    for _ in range(rounds):
        w, c = time.perf_counter(), time.process_time()
        function()
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    return float(np.median(wall)), float(np.median(cpu))


def interleaved(functions: dict, inputs, calls: int, rounds: int) -> dict:
    """``{name: (wall s, least wall s, CPU s)}`` per call of each ``function(x)``: medians (and the
    least wall time) over ``rounds`` rounds of ``calls`` calls cycling through ``inputs``, the
    functions' order alternating from round to round (so that neither always runs after the
    other, with its caches warm)."""
    import time

    names, samples = list(functions), {name: ([], []) for name in functions}
    for r in range(rounds):
        for name in names if r % 2 == 0 else names[::-1]:
            function = functions[name]
            wall, cpu = time.perf_counter(), time.process_time()
            for i in range(calls):
                function(inputs[i % len(inputs)])
            samples[name][0].append((time.perf_counter() - wall) / calls)
            samples[name][1].append((time.process_time() - cpu) / calls)
    return {name: (float(np.median(w)), float(np.min(w)), float(np.median(c))) for name, (w, c) in samples.items()}


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
