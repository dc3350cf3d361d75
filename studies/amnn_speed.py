"""Benchmark: control steps per second of AMNN, compiled layer loop vs Python ask/tell loop.

The ESM paper runs AMNN with L = 1000 layers x P = 128 agents per control step at 30 Hz on an
RTX 4090. Here both implementations of :class:`drake_mh.reactive.esm.AMNN` run the closed loop
of scenario 1 (``self_motion``, h1 = 10, 161 steps of Δt = 0.028 s, the sphere constrains the
arm from t ≈ 1.3 s) on one CPU core, in the same process and back to back:

* ``compiled``: all layers of a step in one numba call (:mod:`drake_mh.reactive.esm.amnn_compiled`);
* ``python``: ARO-amnn through the ask/tell loop of :func:`drake_mh.optim.base.run`.

A control step is what ``run_esm`` times: Drake's distance query at ``θ_prev``, building the
rows of eq. (9), and the solve. Reported per implementation: steps/s = 1 / mean step time
(wall clock), the mean solve time, and steps per CPU-second (process CPU time of the whole
loop, which also pays the loop's bookkeeping: less sensitive to other jobs on a shared
machine than the wall clock). Both implementations draw the same random numbers, so they
take identical steps (checked: ``identical``) and do identical work; the repetitions
alternate their order.

Target: >= 30 control steps per second at L = 1000 x P = 128 on one core.

Run: ``drake-mh study amnn_speed [--quick]`` or ``python studies/amnn_speed.py [--quick]``.
"""

from __future__ import annotations

import os
import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import finished, markdown_table

BUDGETS = {"200x32": (200, 32), "1000x128": (1000, 128), "50x16": (50, 16)}
REPEATS, QUICK_REPEATS = 3, 1
QUICK_STEPS = 20
H1 = 10.0


def _one(robot, scenario, layers: int, agents: int, compiled: bool, steps: int | None) -> tuple:
    """One closed-loop run; returns the run and its process CPU time [s]."""
    from drake_mh.reactive import AMNN, run_esm

    cpu = time.process_time()
    run = run_esm(robot, scenario, AMNN(layers=layers, agents=agents, compiled=compiled), seed=0, steps=steps,
                  verify=False)
    return run, time.process_time() - cpu


def run_case(case: Case) -> dict:
    """Both implementations on one budget, alternating, ``REPEATS`` times."""
    import drake_mh
    from drake_mh.reactive import ESMConfig, get_scenario

    layers, agents = BUDGETS[case["budget"]]
    robot = drake_mh.load_robot("panda")
    scenario = get_scenario("self_motion", config=ESMConfig(h1=H1))
    steps = QUICK_STEPS if case.quick else None
    for compiled in (True, False):                       # numba caches loaded, Drake warmed up
        _one(robot, scenario, 5, 4, compiled, 2)
    load = os.getloadavg()[0]
    runs = {True: [], False: []}
    for rep in range(QUICK_REPEATS if case.quick else REPEATS):
        for compiled in ((True, False) if rep % 2 == 0 else (False, True)):
            runs[compiled].append(_one(robot, scenario, layers, agents, compiled, steps))
    row = dict(layers=layers, agents=agents, load=float(np.mean([load, os.getloadavg()[0]])))
    for compiled, name in ((True, "compiled"), (False, "python")):
        step_time = np.concatenate([r.step_time for r, _ in runs[compiled]])
        solve_time = np.concatenate([r.solve_time for r, _ in runs[compiled]])
        cpu = sum(c for _, c in runs[compiled])
        row[f"{name}_steps_per_s"] = float(1.0 / np.mean(step_time))
        row[f"{name}_solve_ms"] = float(1e3 * np.mean(solve_time))
        row[f"{name}_cpu_steps_per_s"] = float(len(step_time) / cpu)
    row["steps"] = len(runs[True][0][0].step_time)
    row["ratio"] = row["compiled_steps_per_s"] / row["python_steps_per_s"]
    row["ratio_cpu"] = row["compiled_cpu_steps_per_s"] / row["python_cpu_steps_per_s"]
    first = runs[True][0][0]
    row["identical"] = all(np.array_equal(first.theta, r.theta) for c in (True, False) for r, _ in runs[c])
    row["nfe"] = int(first.nfe[0])
    row["time"] = 1.0 / row["compiled_steps_per_s"]       # [s] per control step, compiled
    row["success"] = row["compiled_steps_per_s"] >= 30.0
    return row


def summarize(records: list[dict]) -> str:
    """The printed table: steps/s of both implementations and their ratio, per budget."""
    rows = sorted(finished(records), key=lambda r: r["layers"] * r["agents"])
    lines = ["AMNN on scenario 1, one core: control steps per second (query + rows + solve), compiled vs "
             "Python ask/tell loop, same process; load = 1-min load average of the machine.", ""]
    lines += markdown_table(
        ["L x P", "steps", "compiled steps/s", "Python steps/s", "ratio", "compiled solve [ms]", "Python solve [ms]",
         "compiled steps/CPU-s", "Python steps/CPU-s", "ratio (CPU)", "identical", "load"],
        [[f"{r['layers']} x {r['agents']}", r["steps"], f"{r['compiled_steps_per_s']:.1f}", f"{r['python_steps_per_s']:.1f}",
          f"{r['ratio']:.2f}", f"{r['compiled_solve_ms']:.2f}", f"{r['python_solve_ms']:.2f}",
          f"{r['compiled_cpu_steps_per_s']:.1f}", f"{r['python_cpu_steps_per_s']:.1f}", f"{r['ratio_cpu']:.2f}",
          r["identical"], f"{r['load']:.1f}"] for r in rows])
    paper = [r for r in rows if (r["layers"], r["agents"]) == (1000, 128)]
    if paper:
        r = paper[0]
        lines += ["", f"target >= 30 steps/s at L = 1000 x P = 128: {r['compiled_steps_per_s']:.1f} (wall), "
                      f"{r['compiled_cpu_steps_per_s']:.1f} per CPU-second"]
    return "\n".join(lines)


study = Study(
    name="amnn_speed",
    run=run_case,
    grid={"budget": ["200x32", "1000x128"]},
    quick_grid={"budget": ["50x16"]},
    fields=Fields(method="budget", time="time", rank=False),
    description=(
        "Control steps per second of AMNN (ESM paper, eqs. 12-21) on scenario 1, the compiled layer "
        "loop against the Python ask/tell loop in the same process (identical steps), at our study "
        "budget L = 200 x P = 32 and the paper's L = 1000 x P = 128. Cases run one at a time "
        "(max_workers=1) so that measurements never overlap."
    ),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
