"""The whole ``solve_motion`` call with defaults: search, verification, retiming, certification.

What a user waits for is the whole call, not the search alone. Every case is one warm
``solve_motion(problem, "rrt_connect", seed=...)`` (its first call per robot and retimer in a
process runs once untimed, and each retimer once on its path: compilation, imports, program
builds) with one ``retime`` choice (the study's "method"): ``toppra`` (the default,
``retime=True``: toppra, ruckig where toppra's spline or trajectory cannot be certified),
``ruckig`` (jerk-limited, on the straight segments) and ``none`` (``retime=False``: the
certified path alone). Problems: the generated ``bookshelf_small``,
``table_pick`` and ``cage`` sets of the capsule Panda
(:func:`drake_mh.planning.problems.problem_set`) and, with ``DRAKE_MH_MBM_ARCHIVE`` set to the
``vamp-planner`` source distribution, the original MotionBenchMaker Panda problems (robot: the
Panda with MotionBenchMaker's hand; never downloaded here).

Recorded per case: verified success; the wall-clock and process-CPU seconds of the whole call;
the search (``planning_time``); ``verify_time`` and its parts
(:data:`drake_mh.planning.verify.VERIFY_PARTS`: path certification, retiming, limit
certification, trajectory clearance); the CPU model and the 1-minute load average.

Before/after: ``python studies/whole_call.py --compare OTHER_CHECKOUT [--problems N]`` runs
the default call in two worker processes, one importing drake_mh from ``OTHER_CHECKOUT`` and
one from this checkout, on the same problems, alternately (the order swapped every problem, so
both share the machine's load), and prints per set the median and p95 of the whole call and of
each part, side by side (the workers use only public names both checkouts have).

Run: ``drake-mh study whole_call [--quick]`` or ``python studies/whole_call.py [--quick]``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import (cpu_and_load, finished, group_by, markdown_table, median, p95,
                                           values)

TIMEOUT = 10.0
"""[s] per plan."""
GENERATED = ("bookshelf_small", "table_pick", "cage")
PROBLEMS = 5
"""problems per generated set and per MotionBenchMaker set."""
SET_SEED = 2024
RETIMES = {"toppra": True, "ruckig": "ruckig", "none": False}
"""the study's methods: ``retime`` argument of each."""
PARTS = ("path_certification", "retiming", "limit_certification", "trajectory_clearance")
"""``info["verify_parts"]`` keys (:data:`drake_mh.planning.verify.VERIFY_PARTS`)."""
MBM_ROBOT = "panda_hand_mbm"


def _mbm_archive() -> str | None:
    path = os.environ.get("DRAKE_MH_MBM_ARCHIVE")
    return path if path and os.path.exists(path) else None


def _sets() -> list[tuple[str, str]]:
    """``(robot, set)`` pairs: the generated sets, then MotionBenchMaker's with the archive."""
    pairs = [("panda", name) for name in GENERATED]
    if _mbm_archive():
        from drake_mh.planning.problems import MBM_SETS

        pairs += [(MBM_ROBOT, f"mbm/{name}") for name in MBM_SETS]
    return pairs


_CACHE: dict = {"sets": {}, "warm": set()}


def _problem(robot: str, name: str, index: int, count: int = PROBLEMS):
    """One problem of a set, each set built once per process."""
    key = (robot, name)
    if key not in _CACHE["sets"]:
        from drake_mh.planning.problems import motionbenchmaker_set, problem_set

        _CACHE["sets"][key] = (motionbenchmaker_set(_mbm_archive(), name[4:], robot=robot, count=count)
                               if name.startswith("mbm/") else problem_set(name, robot, count=count, seed=SET_SEED))
    found = _CACHE["sets"][key]
    if index >= len(found):
        raise LookupError(f"{name}: only {len(found)} valid problems for {robot}")
    return found[index]


def _warm_retimers(robot, path) -> None:
    """Run each retimer once on ``path`` (untimed): the warm-up call may not reach one (its
    verification can refuse toppra's spline before solving), and its first call in a process
    imports and builds what later calls reuse."""
    from drake_mh.errors import DrakeMhError
    from drake_mh.trajectories import retime

    if path is None or len(path) < 2:
        return
    for method in ("toppra", "ruckig"):
        try:
            retime(path, robot, method)
        except DrakeMhError:  # a path that cannot be retimed warms what it reached
            continue


def measure(robot: str, name: str, index: int, retime="toppra", seed: int = 0, count: int = PROBLEMS) -> dict:
    """One warm whole call: wall and CPU seconds around it, the search, the verification and its
    parts (NaN where a checkout does not time a part)."""
    from drake_mh.planning import solve_motion

    problem = _problem(robot, name, index, count)
    if (robot, retime) not in _CACHE["warm"]:  # compile / build once per process, untimed
        warm = solve_motion(problem, "rrt_connect", seed=seed, timeout=TIMEOUT, retime=RETIMES[retime])
        _warm_retimers(problem.robot, warm.path)
        _CACHE["warm"].add((robot, retime))
    load = load_average()
    wall, cpu = time.perf_counter(), time.process_time()
    result = solve_motion(problem, "rrt_connect", seed=seed, timeout=TIMEOUT, retime=RETIMES[retime])
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    parts = result.info.get("verify_parts", {})
    record = {"success": bool(result.success), "total": wall, "total_cpu": cpu, "search": result.planning_time,
              "verify": result.verify_time, "retimer": getattr(result.trajectory, "method", None),
              "min_clearance": result.min_clearance, "message": result.message[:120],
              "load_average": float(np.nanmean([load, load_average()])), "cpu": cpu_model()}
    record.update({part: float(parts.get(part, float("nan"))) for part in PARTS})
    return record


def run(case: Case) -> dict:
    record = measure(case["robot"], case["set"], case["problem"], case["method"], seed=case.seed)
    record.update(method=case["method"], time=record["total"], error=record["total"] if record["success"]
                  else float("nan"), nfe=0)
    return record


# --- summary --------------------------------------------------------------------------------------

COLUMNS = (("total", "whole call"), ("total_cpu", "CPU"), ("search", "search"), ("verify", "verify"),
           *((p, p.replace("_", " ")) for p in PARTS))


def _cells(group: list[dict]) -> list[str]:
    return [f"{median(values(group, key, 1e3)):.2f} / {p95(values(group, key, 1e3)):.2f}" for key, _ in COLUMNS]


def summarize(records: list[dict]) -> str:
    ok = finished(records)
    lines = ["Whole `solve_motion(problem, \"rrt_connect\")` call per set and retimer, warm: median / p95 [ms].", ""]
    rows = []
    for (robot, name, method), group in group_by(ok, "robot", "set", "method").items():
        wins = sum(r["success"] for r in group)
        rows.append([robot, name, method, f"{wins}/{len(group)}", *_cells(group)])
    lines += markdown_table(["robot", "set", "retime", "verified", *(label for _, label in COLUMNS)], rows)
    lines += ["", cpu_and_load(ok)]
    return "\n".join(lines)


study = Study(
    name="whole_call",
    run=run,
    grid=[{"robot": robot, "set": name, "problem": i, "method": m}
          for robot, name in _sets() for i in range(PROBLEMS) for m in RETIMES],
    quick_grid=[{"robot": "panda", "set": "table_pick", "problem": 0, "method": m} for m in RETIMES],
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe",
                  instance=("robot", "set", "problem"), rank=False, error_unit="s"),
    description=("The whole solve_motion call (search, verification, retiming, certification) per retimer, "
                 "warm, with the split of its verification; error = wall seconds of a verified call."),
    summarize=summarize,
    max_workers=1,
)


# --- before / after in one run --------------------------------------------------------------------


def _worker() -> None:
    """Read one JSON case per line, answer one JSON record per line (``--worker``)."""
    for line in sys.stdin:
        case = json.loads(line)
        try:
            record = measure(case["robot"], case["set"], case["problem"], case["retime"], count=case["count"])
        except LookupError as exc:
            record = {"skipped": str(exc)}
        print(json.dumps(record), flush=True)


def compare(before: str, problems: int = PROBLEMS, retime: str = "toppra") -> str:
    """The default call from checkout ``before`` and from this one, alternately on the same
    problems (module docstring); a markdown table of both."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    workers = {}
    for label, root in (("before", os.path.abspath(before)), ("after", here)):
        env = dict(os.environ, PYTHONPATH=root)
        workers[label] = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--worker"], env=env,
                                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=root)
    records = []
    order = ["before", "after"]
    try:
        for robot, name in _sets():
            for index in range(problems):
                order.reverse()
                for label in order:
                    workers[label].stdin.write(json.dumps({"robot": robot, "set": name, "problem": index,
                                                           "retime": retime, "count": problems}) + "\n")
                    workers[label].stdin.flush()
                    record = json.loads(workers[label].stdout.readline())
                    if "skipped" not in record:
                        records.append(dict(record, code=label, robot=robot, set=name, problem=index))
    finally:
        for worker in workers.values():
            worker.stdin.close()
            worker.wait()
    rows = []
    for (robot, name), group in group_by(records, "robot", "set").items():
        by = group_by(group, "code")
        for label in ("before", "after"):
            mine = by.get(label, [])
            rows.append([robot, name, label, f"{sum(r['success'] for r in mine)}/{len(mine)}", *_cells(mine)])
    for robot, group in [*group_by(records, "robot").items(), ("all", records)]:
        for label in ("before", "after"):
            mine = [r for r in group if r["code"] == label]
            rows.append([robot, "all", label, f"{sum(r['success'] for r in mine)}/{len(mine)}", *_cells(mine)])
    lines = [f"retime={retime!r}; before: {os.path.abspath(before)}, after: {here}; median / p95 [ms]", ""]
    lines += markdown_table(["robot", "set", "code", "verified", *(label for _, label in COLUMNS)], rows)
    lines += ["", cpu_and_load(records)]
    return "\n".join(lines)


if __name__ == "__main__":
    if "--worker" in sys.argv:
        _worker()
    elif "--compare" in sys.argv:
        args = sys.argv[1:]
        count = int(args[args.index("--problems") + 1]) if "--problems" in args else PROBLEMS
        print(compare(args[args.index("--compare") + 1], count))
    else:
        from drake_mh.cli import run_script

        run_script(study)
