"""IK comparison (demo): Drake IK (SNOPT) vs the hybrid vs two metaheuristics on the Panda.

Twelve Panda targets (poses of random configurations within the limits, full 6-D pose at
1 mm / 0.01 rad, the default tolerances), four methods, each result verified with Drake:

* ``drake_snopt``: Drake ``InverseKinematics`` + SNOPT, random restarts;
* ``hybrid``: population search + batched Levenberg–Marquardt (``drake_mh.ik.hybrid``);
* ``de`` and ``pso``: metaheuristic IK (framework paper, Algorithm 1) with a budget of 20,000
  evaluations, stopped as soon as the tolerances are met.

Every method gets 0.5 s. The full study (``grid``) uses 50 targets; the demo runs the quick
grid (12 targets) in seconds. The full comparison is ``studies/ik_benchmark.py``.

Run: ``drake-mh study ik_comparison [--quick]`` or ``python studies/ik_comparison.py [--quick]``.
"""

from __future__ import annotations

import numpy as np

import drake_mh
from drake_mh.ik import IKProblem, solve_ik
from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import finished, group_by, markdown_table, mean, median, ratio, share, values

METHODS = ("drake_snopt", "hybrid", "de", "pso")
TIMEOUT = 0.5  # [s]
BUDGET = 20_000  # evaluations (metaheuristics)
TARGET_SEED = 7

_ROBOT: list = []
_WARM: set = set()


def _panda():
    if not _ROBOT:
        _ROBOT.append(drake_mh.load_robot("panda"))
    return _ROBOT[0]


def run(case: Case) -> dict:
    """Solves one target with one method (targets depend on the target index only)."""
    robot = _panda()
    q_t = robot.random_configurations(1, np.random.default_rng([TARGET_SEED, case["target"]]))[0]
    problem = IKProblem(robot, robot.fk(q_t))
    method = case["method"]
    budget = BUDGET if method in ("de", "pso") else None
    if method not in _WARM:  # imports and compiled kernels are loaded outside the timing
        _WARM.add(method)
        solve_ik(problem, method, seed=0, budget=2 if method.startswith("drake") else 200)
    result = solve_ik(problem, method, seed=case.seed, budget=budget, timeout=TIMEOUT)
    out = {"success": result.success, "time": result.time, "nfe": result.nfe,
           "error": result.position_error + result.orientation_error,
           "position_error": result.position_error, "orientation_error": result.orientation_error}
    if len(result.history_nfe):
        out["history_nfe"] = result.history_nfe
        out["history_best"] = result.history_best
    return out


def summarize(records: list[dict]) -> str:
    """Per-method success, mean / median time, and the time ratio against Drake SNOPT."""
    groups = group_by(records, "method")
    means = {m: mean(values(finished(g), "time")) for m, g in groups.items()}
    rows = [[m, len(g), f"{100 * share(g):.0f}", f"{1e3 * means[m]:.2f}",
             f"{median(values(finished(g), 'time', 1e3)):.2f}", f"{ratio(means.get('drake_snopt'), means[m]):.1f}x"]
            for m, g in groups.items()]
    return "\n".join(["Panda, full pose at 1 mm / 0.01 rad, 0.5 s per solve; success verified with Drake. "
                      "`vs SNOPT` = mean time of drake_snopt / mean time of the method (same run).", ""]
                     + markdown_table(["method", "targets", "success %", "mean time [ms]", "median time [ms]",
                                       "vs SNOPT"], rows))


study = Study(
    name="ik_comparison",
    run=run,
    grid={"target": range(50), "method": list(METHODS)},
    quick_grid={"target": range(12), "method": list(METHODS)},
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe", error_unit="m + rad",
                  conditions=f"{TIMEOUT} s per solve, DE and PSO also at most {BUDGET:,} evaluations; success = "
                             "pose verified with Drake within 1 mm and 0.01 rad"),
    description=(
        "Inverse kinematics on the Panda (full pose, 1 mm / 0.01 rad): Drake InverseKinematics with SNOPT, "
        "the hybrid (population search + batched Levenberg-Marquardt), and the metaheuristics DE and PSO "
        "(framework paper, Algorithm 1; 20,000 evaluations). Every result is verified with Drake. "
        "'error' = position error [m] + orientation error [rad]."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
