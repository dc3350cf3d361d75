"""What a first call costs: every kernel's compile time from an empty numba cache, its load time
from the cache, and its size on disk.

Per kernel family of :data:`drake_mh.study.warmup.GROUPS` (each a small workload calling its
kernels as the library does), each step in a fresh process (``python -m drake_mh.study.warmup``):

1. the family's workload with an empty cache (``DRAKE_MH_CACHE`` a new folder: numba's cache and
   the derived caches empty, as on a new machine): wall and CPU seconds, and the kernels that
   Python called and that compiled (entry points; their callees compile inside them), each with
   its argument types (specializations);
2. the same workload again with that cache: what every later process pays;
3. per entry point, in a new process with a new empty cache: ``dispatcher.compile`` of its
   recorded signatures (compile seconds, its callees included), then in another new process from
   that cache (load seconds); the cache files of the entry point itself (what a process loads)
   and of the whole folder (the callees' entries too, used only to compile other callers).

The families a first plan needs (:data:`drake_mh.study.warmup.FIRST_PLAN`: ``MotionProblem``,
``solve_motion(problem, "rrt_connect")``, its verification and retiming) are the quick grid.
Cases run one at a time (their compile times would share the cores otherwise); the CPU model
and the 1-minute load average are recorded (shared machines: CPU seconds hold better than wall).

``DRAKE_MH_FIRST_CALL_GROUPS=a,b`` measures those families instead, in both grids (names of
``drake-mh warmup --list``; an unknown name is an error that lists them).

Run: ``drake-mh study first_call [--quick]`` or ``python studies/first_call.py [--quick]``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.warmup import FIRST_PLAN, GROUPS

def _groups(families) -> list[str]:
    """``families``, or instead those of ``DRAKE_MH_FIRST_CALL_GROUPS`` (comma-separated), in the order of
    :data:`~drake_mh.study.warmup.GROUPS`."""
    from drake_mh.errors import InvalidArgument

    chosen = [g.strip() for g in os.environ.get("DRAKE_MH_FIRST_CALL_GROUPS", "").split(",") if g.strip()]
    unknown = sorted(set(chosen) - set(GROUPS))
    if unknown:
        raise InvalidArgument(f"DRAKE_MH_FIRST_CALL_GROUPS: unknown famil{'y' if len(unknown) == 1 else 'ies'} "
                              f"{', '.join(unknown)}; choose among {', '.join(GROUPS)}")
    return [g for g in GROUPS if g in chosen] if chosen else list(families)


PROBE_TIMEOUT = 1800.0
"""[s] the longest one probe process may take (a family that compiles for longer fails the case)."""


def _probe(cache: Path, out: Path, *arguments: str) -> dict:
    """Runs ``python -m drake_mh.study.warmup ARGUMENTS --out OUT`` with ``DRAKE_MH_CACHE=cache``
    (a user's ``NUMBA_CACHE_DIR`` set aside); its JSON record, with the process's wall time."""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "DRAKE_MH_NUMBA_CACHE_DIR")}
    env["DRAKE_MH_CACHE"] = str(cache)
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "drake_mh.study.warmup", *arguments, "--out", str(out)], env=env,
                          capture_output=True, text=True, timeout=PROBE_TIMEOUT)
    if not out.exists():
        raise RuntimeError(f"probe {' '.join(arguments)} wrote nothing (exit {done.returncode}): {done.stderr[-2000:]}")
    record = json.loads(out.read_text())
    record["process_seconds"] = time.perf_counter() - start
    return record


def _size(folder: Path, pattern: str = "*") -> int:
    return sum(f.stat().st_size for f in folder.rglob(pattern) if f.is_file())


def run(case: Case) -> dict:
    """One family: compile and load times of the family and of each of its entry points."""
    group = case["group"]
    with tempfile.TemporaryDirectory(prefix="first_call_") as tmp:
        tmp = Path(tmp)
        signatures = tmp / "signatures.pkl"
        cold = _probe(tmp / "group", tmp / "cold.json", "--group", group, "--signatures", str(signatures))
        warm = _probe(tmp / "group", tmp / "warm.json", "--group", group)
        kernels = []
        for module, qualname, count, _, _ in cold["kernels"]:
            name = f"{module}:{qualname}"
            cache = tmp / f"k{len(kernels)}"
            compiled = _probe(cache, tmp / f"c{len(kernels)}.json", "--kernel", name, "--signatures", str(signatures))
            loaded = _probe(cache, tmp / f"l{len(kernels)}.json", "--kernel", name, "--signatures", str(signatures))
            kernels.append({"kernel": name, "specializations": count, "compile": compiled["seconds"],
                            "compile_cpu": compiled["cpu"], "load": loaded["seconds"], "load_cpu": loaded["cpu"],
                            "loaded_from_cache": not loaded["compiled"],
                            "entry_bytes": _size(cache, f"{module.rsplit('.', 1)[1]}.{qualname}-*"),
                            "cache_bytes": _size(cache)})
        return {
            "success": cold["error"] is None and warm["error"] is None,
            "time": cold["cpu"],
            "error": 0.0,
            "message": cold["error"] or warm["error"] or "",
            "compile [s]": cold["seconds"],
            "compile cpu [s]": cold["cpu"],
            "load [s]": warm["seconds"],
            "load cpu [s]": warm["cpu"],
            "cache bytes": _size(tmp / "group" / "numba"),
            "kernels": json.dumps(kernels),
            "cpu": cpu_model(),
            "load_average": load_average(),
        }


def summarize(records: list[dict]) -> str:
    """The families' compile and load times, then one row per entry point."""
    ok = [r for r in records if r.get("status") == "ok"]
    if not ok:
        return "no finished case"
    ok.sort(key=lambda r: list(GROUPS).index(r["group"]))
    loads = [r["load_average"] for r in ok]
    lines = [f"CPU: {ok[0]['cpu']}; 1-min load average during the cases: {min(loads):.1f}-{max(loads):.1f}", "",
             "| family | compile, empty cache [s] (CPU) | later processes [s] (CPU) | cache [MB] |", "|---|---|---|---|"]
    for r in ok:
        lines.append(f"| {r['group']} | {r['compile [s]']:.1f} ({r['compile cpu [s]']:.1f}) | {r['load [s]']:.1f} "
                     f"({r['load cpu [s]']:.1f}) | {r['cache bytes'] / 1e6:.1f} |")
    first = [r for r in ok if r["group"] in FIRST_PLAN]
    if len(first) == len(FIRST_PLAN):
        lines += ["", f"A first plan's families ({', '.join(FIRST_PLAN)}): "
                      f"{sum(r['compile cpu [s]'] for r in first):.0f} s CPU to compile, one family after the other."]
    lines += ["", "Entry points (called from Python), each compiled in a new process with an empty cache (its "
                  "callees included), then loaded in another:", "",
              "| family | kernel | specializations | compile [s] (CPU) | load [s] (CPU) | entry [kB] | with callees [kB] |",
              "|---|---|---|---|---|---|---|"]
    for r in ok:
        for k in json.loads(r["kernels"]):
            lines.append(f"| {r['group']} | {k['kernel'].split(':')[1]} | {k['specializations']} | {k['compile']:.1f} "
                         f"({k['compile_cpu']:.1f}) | {k['load']:.2f} ({k['load_cpu']:.2f}) | "
                         f"{k['entry_bytes'] / 1e3:.0f} | {k['cache_bytes'] / 1e3:.0f} |")
    return "\n".join(lines)


study = Study(
    name="first_call",
    run=run,
    grid={"group": _groups(GROUPS)},
    quick_grid={"group": _groups(FIRST_PLAN)},
    fields=Fields(method="group", success="success", time="time", error="error", rank=False, error_unit=""),
    description=(
        "Compile time of every kernel family and entry point from an empty numba cache, load time from the "
        "cache and size on disk, each in fresh processes. 'time' is the family's compile CPU seconds."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
