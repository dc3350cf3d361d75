"""The compiled TOPP-RA against the toppra package: ``retime(W, panda, "toppra")`` and the solve alone.

On ``PATHS`` random Panda paths (3-8 waypoints uniform in the central ``SPREAD`` of every joint
range, seeded: 130-240 gridpoints, near the ~150 of a planned path's retiming; the path :func:`drake_mh.trajectories.paths.joint_path` makes and toppra's
gridpoints), in one process, interleaved rounds (order alternating), after a first call of each:

* ``retime``: the whole ``retime(W, panda, "toppra")`` (spline, gridpoints, rows, solve, time
  law, certification, repairs) with the solve by the compiled core (``backend="auto"``, what a
  user gets where the core is built) and with the toppra package, everything else the same (the
  package path chosen by wrapping :func:`drake_mh.trajectories.toppra_solve.solve_sd`; the
  environment switch would also swap the dynamics kernels);
* ``solve``: :func:`~drake_mh.trajectories.toppra_solve.solve_sd` on the same prepared rows
  (velocity, acceleration, torque; one interior check point), each backend;
* ``core``: the core's ``topp_ra`` alone on the rows already stacked (what Python adds around it
  is the rest of ``solve``).

Reported: ms per call (median over rounds of the mean over the paths, wall and process CPU),
the least wall time, the ratio compiled / package, whether every ``ṡ`` agreed within 1e-9
relative, the median number of gridpoints and the 1-minute load average before and after.
Results: docs/native.md.

Run: ``drake-mh study toppra_solver_speed [--quick]`` or ``python studies/toppra_solver_speed.py [--quick]``.
"""

from __future__ import annotations

from unittest import mock

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, interleaved, load_average
from drake_mh.study.report.summary import cell, cpu_and_load, finished, markdown_table

PATHS = 10
SPREAD = 0.15
ROUNDS, QUICK_ROUNDS = 9, 3
CASES = ("retime", "solve", "core")


def _paths(robot):
    rng = np.random.default_rng(0)
    mid, half = 0.5 * (robot.lower + robot.upper), 0.5 * (robot.upper - robot.lower)
    return [mid + rng.uniform(-SPREAD, SPREAD, (int(rng.integers(3, 9)), robot.nq)) * half for _ in range(PATHS)]


def _rows(robot, W):
    from drake_mh.trajectories.limits_for import enforced_limits
    from drake_mh.trajectories.paths import joint_path
    from drake_mh.trajectories.toppra_solve import stage_rows
    from drake_mh.trajectories.toppra_time import _gridpoints

    table = enforced_limits(robot, "toppra", W, None, None, None)
    spline, s_way = joint_path(W, robot, "toppra", bc_type="not-a-knot")
    gp = _gridpoints(spline, s_way, None)
    rows = stage_rows(robot, spline, gp, table["velocity"] * 0.99, table["acceleration"] * 0.99, table["torque"],
                      np.linspace(0.0, 1.0, 3))
    return rows, spline


def run_case(case: Case) -> dict:
    """One comparison on the ``PATHS`` paths: ms per call of both, ratios, same answers."""
    import drake_mh
    from drake_mh._support.native import compiled_core
    from drake_mh.trajectories import retime, toppra_solve, toppra_time

    row = dict(case=case["case"], cpu=cpu_model(), load_average=load_average())
    core = compiled_core()
    row["built"] = core is not None
    if core is None:
        return row
    robot = drake_mh.load_robot("panda")
    paths = _paths(robot)
    rounds = QUICK_ROUNDS if case.quick else ROUNDS
    solve_sd = toppra_solve.solve_sd
    package = mock.patch.object(toppra_time, "solve_sd", lambda rows, spline, backend: solve_sd(rows, spline, "toppra"))
    prepared = [_rows(robot, W) for W in paths]
    row["gridpoints"] = float(np.median([len(r.gridpoints) for r, _ in prepared]))
    row["same"] = all(np.allclose(solve_sd(r, s, "compiled")[0], solve_sd(r, s, "toppra")[0], rtol=1e-9, atol=0)
                      for r, s in prepared)
    stacked = [(r.gridpoints,) + r.canonical() for r, _ in prepared]
    if case["case"] == "retime":
        def with_package(k):
            with package:
                return retime(paths[k], robot, "toppra")

        functions = {"compiled": lambda k: retime(paths[k], robot, "toppra"), "package": with_package}
        row["same"] = row["same"] and all(
            abs(functions["compiled"](k).duration / with_package(k).duration - 1) < 1e-9 for k in range(PATHS))
    else:
        compiled = ((lambda k: solve_sd(*prepared[k], "compiled")) if case["case"] == "solve"
                    else (lambda k: core.topp_ra(*stacked[k])))
        functions = {"compiled": compiled, "package": lambda k: solve_sd(*prepared[k], "toppra")}
    inputs = list(range(PATHS))
    for f in functions.values():  # a first call of each (imports, caches)
        f(inputs[0])
    for name, measured in interleaved(functions, inputs, len(inputs), rounds).items():
        row.update({f"{name}_{kind}_ms": 1e3 * value for kind, value in zip(("wall", "least", "cpu"), measured)})
    row.update(load_after=load_average(), time=row["compiled_wall_ms"] * 1e-3)
    return row


def summarize(records: list[dict]) -> str:
    """Per case: ms per call of both, their ratios, same answers."""
    rows = [r for r in finished(records) if r.get("built")]
    if not rows:
        return "Nothing measured: the compiled core drake_mh._native is not built (or DRAKE_MH_COMPILED_CORE=0)."
    header = ["case", "gridpoints"]
    for kind in ("wall", "cpu"):
        header += [f"package {kind} ms", f"compiled {kind} ms", f"ratio ({kind})"]
    table = []
    for r in rows:
        line = [r["case"], cell(r["gridpoints"], ".0f")]
        for kind in ("wall", "cpu"):
            old, new = r[f"package_{kind}_ms"], r[f"compiled_{kind}_ms"]
            line += [cell(old, ".3g"), cell(new, ".3g"), cell(new / old, ".3f")]
        table.append(line + [f"{r['package_least_ms']:.3g} / {r['compiled_least_ms']:.3g}", r["same"],
                             f"{r['load_average']:.1f}-{r['load_after']:.1f}"])
    lines = [f"Compiled TOPP-RA vs the toppra package on {PATHS} random Panda paths, one process, interleaved "
             "rounds; ms per call (median of rounds); ratio = compiled / package.", ""]
    lines += markdown_table(header + ["least wall package / compiled", "same sd", "load"], table)
    lines += ["", cpu_and_load(rows, loads=("load_average", "load_after"))]
    return "\n".join(lines)


study = Study(
    name="toppra_solver_speed",
    run=run_case,
    grid={"case": list(CASES)},
    quick_grid={"case": ["solve"]},
    fields=Fields(method="case", time="time", rank=False),
    description=(
        "The compiled TOPP-RA (cpp/topp.hpp) against the toppra package it ports: the whole retime(W, panda, "
        "'toppra'), the solve on prepared rows, and the core's solver alone, on random Panda paths, same process, "
        "interleaved rounds, CPU time beside wall time (max_workers=1)."
    ),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
