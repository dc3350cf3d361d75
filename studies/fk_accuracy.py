"""FK accuracy: the batched kernel against Drake on every bundled robot.

For each robot and replicate, random configurations uniformly within the joint limits
(drawn from the case's instance stream) are evaluated by ``robot.batch.fk`` /
``robot.batch.jacobian`` and by Drake one configuration at a time (``robot.fk_drake`` /
``robot.jacobian_drake``; ``robot.fk`` is a compiled kernel too). Records the largest absolute
difference of the end-effector position [m], of the rotation matrix entries, and of the
Jacobian entries; a case passes when all three are below 1e-9.

Run: ``drake-mh study fk_accuracy [--quick]`` or ``python studies/fk_accuracy.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

import drake_mh
from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import finished, group_by, markdown_table

TOLERANCE = 1e-9
CONFIGURATIONS = 2000
QUICK_CONFIGURATIONS = 200


def run(case: Case) -> dict:
    """Compares the batched kernel with Drake on one robot and one set of configurations."""
    robot = drake_mh.load_robot(case["robot"])
    n = QUICK_CONFIGURATIONS if case.quick else CONFIGURATIONS
    Q = robot.random_configurations(n, case.instance_rng)  # (n, nq)
    robot.batch.fk(Q[:1])  # compile / load the kernel before timing
    start = time.perf_counter()
    T_batch = robot.batch.fk(Q)  # (n, 4, 4)
    J_batch = robot.batch.jacobian(Q)  # (n, 6, nq)
    batch_time = time.perf_counter() - start
    start = time.perf_counter()
    T_drake = np.stack([robot.fk_drake(q) for q in Q])
    J_drake = np.stack([robot.jacobian_drake(q) for q in Q])
    drake_time = time.perf_counter() - start
    position_error = float(np.max(np.abs(T_batch[:, :3, 3] - T_drake[:, :3, 3])))
    rotation_error = float(np.max(np.abs(T_batch[:, :3, :3] - T_drake[:, :3, :3])))
    jacobian_error = float(np.max(np.abs(J_batch - J_drake)))
    error = max(position_error, rotation_error, jacobian_error)
    return {
        "nq": robot.nq,
        "configurations": n,
        "success": bool(error < TOLERANCE),
        "error": error,
        "position_error": position_error,
        "rotation_error": rotation_error,
        "jacobian_error": jacobian_error,
        "time": batch_time / n,  # [s] per configuration, FK + Jacobian, batched
        "drake_time": drake_time / n,  # [s] per configuration, FK + Jacobian, Drake loop
    }


def summarize(records: list[dict]) -> str:
    """Per-robot table of the largest differences over all replicates."""
    rows = []
    for robot, group in group_by(records, "robot").items():
        ok = finished(group)
        if not ok:
            rows.append([robot, "-", "-", "-", "-", "-", "raised"])
            continue
        passed = len(ok) == len(group) and all(r["success"] for r in ok)
        rows.append([robot, ok[0]["nq"], sum(r["configurations"] for r in ok)]
                    + [f"{max(r[k] for r in ok):.2e}" for k in ("position_error", "rotation_error", "jacobian_error")]
                    + ["yes" if passed else "NO"])
    return "\n".join([f"Largest |batched - Drake| over all configurations (pass: every difference < {TOLERANCE:g})", ""]
                     + markdown_table(["robot", "nq", "configurations", "position [m]", "rotation", "Jacobian", "pass"],
                                      rows))


study = Study(
    name="fk_accuracy",
    run=run,
    grid={"robot": drake_mh.available_robots(), "rep": range(5)},
    quick_grid={"robot": drake_mh.available_robots(), "rep": range(1)},
    fields=Fields(method="robot", success="success", time="time", error="error", nfe="configurations", rank=False,
                  error_unit="m, -"),
    description=(
        "Batched forward kinematics and Jacobians (drake_mh.kinematics.BatchKinematics) against "
        "Drake's MultibodyPlant, one row per bundled robot, on random configurations within the "
        "joint limits. 'error' is the largest absolute difference of position [m], rotation-matrix "
        "entries and Jacobian entries; 'time' is the batched FK + Jacobian time per configuration [s]."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
