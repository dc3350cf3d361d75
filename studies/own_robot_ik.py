"""IK on robot descriptions as shipped (example-robot-data), at the TRAC-IK protocol.

The arms of ``example-robot-data`` (a test extra) load with their meshes, a hand's fingers
locked (:func:`drake_mh.load_robot` with ``ee_frame``). Each case draws ``TARGETS`` random
configurations within the joint limits (the case's instance stream), takes their FK pose as
the target and solves full-pose IK with a 5 ms timeout and 1e-5 tolerances (position [m],
orientation [rad]) — the TRAC-IK README's protocol, no collision check; the mean time
includes failures (which run to the timeout). Success is verified with Drake by
:func:`drake_mh.solve_ik`. Preparation (compiled kernels, once per process) is not timed.

Run: ``drake-mh study own_robot_ik [--quick]`` or ``python studies/own_robot_ik.py [--quick]``.
"""

from __future__ import annotations

import os

import numpy as np

from drake_mh.robot.examples import load_example_arm
from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import finished, group_by, markdown_table, median, values

ROBOTS = ("panda_hand", "ur5", "xarm7", "kinova")  # drake_mh.robot.examples
METHODS = ("hybrid", "drake_snopt")
TARGETS, QUICK_TARGETS = 100, 10
TIMEOUT = 0.005  # [s]
TOLERANCE = 1e-5  # [m] and [rad]
_ROBOTS: dict = {}


def _robot(name: str):
    if name not in _ROBOTS:
        _ROBOTS[name] = load_example_arm(name)
    return _ROBOTS[name]


def run(case: Case) -> dict:
    """``TARGETS`` full-pose IK problems on one robot with one method."""
    from pydrake.math import RollPitchYaw, RotationMatrix

    from drake_mh.ik import IKProblem, solve_ik

    robot = _robot(case["robot"])
    n = QUICK_TARGETS if case.quick else TARGETS
    Q = robot.random_configurations(n, case.instance_rng)
    solved, times, errors = 0, [], []
    for i, q in enumerate(Q):
        X = robot.fk(q)
        rpy = RollPitchYaw(RotationMatrix(X[:3, :3])).vector()
        problem = IKProblem(robot, X[:3, 3], rpy=rpy, position_tolerance=TOLERANCE,
                            orientation_tolerance=TOLERANCE)
        result = solve_ik(problem, case["method"], seed=i, timeout=TIMEOUT)
        solved += bool(result.success)
        times.append(result.time)
        errors.append(result.position_error)
    return {
        "nq": robot.nq,
        "targets": n,
        "success": solved / n,
        "time": float(np.mean(times)),
        "median_time": float(np.median(times)),
        "error": float(np.median(errors)),
        "load_average": os.getloadavg()[0],
    }


def summarize(records: list[dict]) -> str:
    """Success rate and mean time per robot and method (each case solves a batch of targets)."""
    groups = group_by(finished(records), "robot", "method")
    rows = []
    for key in [(name, method) for name in ROBOTS for method in METHODS if (name, method) in groups]:
        group = groups[key]
        n = sum(r["targets"] for r in group)
        rate = sum(r["success"] * r["targets"] for r in group) / n
        mean_time = sum(r["time"] * r["targets"] for r in group) / n
        rows.append([key[0], group[0]["nq"], key[1], n, f"{100 * rate:.1f} %", f"{1e3 * mean_time:.2f}",
                     f"{1e3 * median(values(group, 'median_time')):.2f}"])
    return "\n".join([f"Full-pose IK, {TIMEOUT * 1e3:g} ms timeout, tolerance {TOLERANCE:g} m / rad (TRAC-IK protocol)",
                      ""] + markdown_table(["robot", "nq", "method", "targets", "success", "mean time [ms]",
                                            "median time [ms]"], rows))


study = Study(
    name="own_robot_ik",
    run=run,
    grid={"robot": list(ROBOTS), "method": list(METHODS), "chunk": range(10)},
    quick_grid={"robot": ["panda_hand", "ur5"], "method": list(METHODS), "chunk": range(1)},
    fields=Fields(method="method", success="success", time="time", error="error", nfe="targets",
                  instance=("robot", "chunk"), group_by=("robot",), error_unit="m",
                  conditions=f"{TIMEOUT * 1e3:g} ms per solve; success = {TOLERANCE:g} m and {TOLERANCE:g} rad"),
    description=(
        "Full-pose IK at the TRAC-IK protocol on robot descriptions loaded as shipped from "
        "example-robot-data (meshes, a hand's fingers locked). 'success' is the fraction of targets "
        "solved within the tolerance (verified with Drake), 'time' the mean solve time [s] "
        "(failures count at their time, at most the timeout), 'error' the median position error [m]."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
