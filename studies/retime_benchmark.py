"""Time parameterization benchmark: toppra vs Drake's Toppra vs ruckig on random Panda paths.

Each replicate draws 7 joint waypoints uniformly in the central 80 % of the Panda's joint
ranges (the same path for every method: the case's instance stream) and times it with

Variants (the study's "method"): ``toppra@100``, ``toppra@1000``, ``drake-toppra@100``,
``drake-toppra@1000``, ``ruckig``:

* ``toppra`` (drake_mh's toppra set-up: seidel solver, velocity/acceleration/torque limits,
  torque with gravity from the plant-compiled RNEA, interior check rows) at 100 and 1000
  gridpoints;
* ``drake-toppra`` (Drake's ``Toppra``, same spline, same gridpoints, same limits) — the baseline;
* ``ruckig`` (jerk-limited, community edition: rest-to-rest through every waypoint, velocity /
  acceleration / jerk limits; it has no torque limit — torque is only reported).

Recorded per case: trajectory duration [s]; computation time of ``retime`` [s] (best of
``REPEATS`` calls, which includes the dense certification) and of the solve alone, and the same
for Drake's Toppra on the same path timed alternately with it (the baseline); the worst
certified ratio over the enforced quantities (a violation is a ratio above 1 + 1e-6, or an
exception); attempts and the time scaling applied. The summary gives medians and ratios
against Drake's Toppra measured in the same run (cases run one at a time: ``max_workers=1``).
Target: toppra <= 10 ms at 100 gridpoints with torque limits, zero violations.

Run: ``drake-mh study retime_benchmark [--quick]`` or ``python studies/retime_benchmark.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

import drake_mh
from drake_mh.study import Case, Fields, Study

WAYPOINTS = 7
SPREAD = 0.8
REPEATS, QUICK_REPEATS = 5, 1
TOL = 1e-6
_ROBOT = {}


def _panda():
    if "panda" not in _ROBOT:
        _ROBOT["panda"] = drake_mh.load_robot("panda")
    return _ROBOT["panda"]


def waypoints(robot, rng) -> np.ndarray:
    """``(7, 7)`` waypoints uniform in the central 80 % of every joint range."""
    mid, half = 0.5 * (robot.lower + robot.upper), 0.5 * (robot.upper - robot.lower)
    return mid + rng.uniform(-SPREAD, SPREAD, size=(WAYPOINTS, robot.nq)) * half


def run(case: Case) -> dict:
    """Retimes one random path with one method; best-of-N timing; certified ratios."""
    robot = _panda()
    W = waypoints(robot, case.instance_rng)  # instance = rep: the same path for every variant
    method, _, grid = case["method"].partition("@")
    grid = int(grid or 0)
    kwargs = {} if method == "ruckig" else {"gridpoints": grid}
    base_grid = grid or 100
    drake_mh.retime(W, robot, method, **kwargs)  # warm-up: imports, numba kernels, Drake objects
    drake_mh.retime(W, robot, "drake-toppra", gridpoints=base_grid)
    times, solve, base_times = [], [], []
    for _ in range(QUICK_REPEATS if case.quick else REPEATS):  # interleaved with the baseline
        start = time.perf_counter()
        traj = drake_mh.retime(W, robot, method, **kwargs)
        times.append(time.perf_counter() - start)
        solve.append(traj.info["solve_time"])
        start = time.perf_counter()
        base = drake_mh.retime(W, robot, "drake-toppra", gridpoints=base_grid)
        base_times.append(time.perf_counter() - start)
    cert = traj.info["certificate"]
    enforced = ("position",) + tuple(traj.info["limits"])
    worst = cert.max_ratio(enforced)
    out = {
        "retimer": method,
        "gridpoints": grid,
        "success": bool(worst <= 1 + TOL),
        "error": worst,
        "time": min(times),
        "solve_time": min(solve),
        "baseline_time": min(base_times),  # Drake's Toppra on the same path, timed alternately
        "time_vs_drake": min(times) / min(base_times),
        "duration_vs_drake": traj.duration / base.duration,
        "duration": traj.duration,
        "attempts": int(traj.info["attempts"]),
        "time_scaling": float(traj.info.get("time_scaling", 1.0)),
        "pieces": len(traj.breaks) - 1,
        **{f"{k}": v for k, v in cert.as_dict().items() if k != "max_ratio"},
    }
    if case["rep"] == 0:
        t, q = traj.sample_uniform(300)
        out["traj_t"], out["traj_q"] = t, q
    return out


METHODS = ("toppra@100", "drake-toppra@100", "toppra@1000", "drake-toppra@1000", "ruckig")


def summarize(records: list[dict]) -> str:
    """Medians per method and gridpoints, and ratios against Drake's Toppra (same path, same run)."""
    ok = [r for r in records if r.get("status") == "ok"]
    failed = [r for r in records if r.get("status") != "ok"]
    by = {}
    for r in ok:
        by.setdefault((r["retimer"], r["gridpoints"]), {})[r["rep"]] = r
    lines = ["| method | gridpoints | cases | duration [s] median | time [ms] median (p95) | solve only [ms] | "
             "duration / Drake | time / Drake | worst certified ratio | violations |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for (method, grid), reps in sorted(by.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        rs = list(reps.values())
        dur_ratio = np.median([r["duration_vs_drake"] for r in rs])
        time_ratio = np.median([r["time_vs_drake"] for r in rs])
        t = np.array([r["time"] for r in rs]) * 1e3
        viol = sum(not r["success"] for r in rs)
        label = "-" if method == "ruckig" else str(grid)
        base_label = "" if method != "ruckig" else " (vs 100)"
        lines.append(
            f"| {method} | {label} | {len(rs)} | {np.median([r['duration'] for r in rs]):.3f} | "
            f"{np.median(t):.2f} ({np.percentile(t, 95):.2f}) | "
            f"{np.median([r['solve_time'] for r in rs]) * 1e3:.2f} | {dur_ratio:.3f}{base_label} | "
            f"{time_ratio:.2f}{base_label} | {max(r['error'] for r in rs):.7f} | {viol} |")
    top = by.get(("toppra", 100), {})
    lines += ["", f"Target: toppra <= 10 ms at 100 gridpoints with torque limits: median "
              f"{np.median([r['time'] for r in top.values()]) * 1e3:.2f} ms, "
              f"{sum(r['time'] <= 0.010 for r in top.values())}/{len(top)} cases within."
              if top else "", f"Cases that raised: {len(failed)}; violations (> 1 + {TOL:g}): "
              f"{sum(not r['success'] for r in ok)}.",
              "Time = best of repeated `retime` calls including the dense certification; "
              "'solve only' leaves the certification out. Duration / time ratios: medians over "
              "paths of the ratio to `drake-toppra` on the same path at the same gridpoints "
              "(ruckig: at 100), the two timed alternately in the same case (robust to load drift)."]
    return "\n".join(x for x in lines if x is not None).strip()


study = Study(
    name="retime_benchmark",
    run=run,
    grid={"method": METHODS, "rep": list(range(30))},
    quick_grid={"method": METHODS, "rep": [0]},
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="attempts",
                  instance=("rep",), lower_is_better=True, rank=False, error_unit=""),
    description=(
        "Time-optimal parameterization of random 7-waypoint Panda paths under velocity, "
        "acceleration and torque limits (gravity included): drake_mh's toppra set-up against "
        "Drake's Toppra (same spline and gridpoints) at 100 and 1000 gridpoints, and ruckig "
        "(jerk-limited, stopping at every waypoint). error = worst certified limit ratio "
        "(<= 1 + 1e-6 passes); time = computation time of retime [s] (certification included)."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
