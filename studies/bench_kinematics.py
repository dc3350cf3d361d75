"""Benchmark: batched FK + Jacobian vs Drake's per-configuration Python loop.

For N in {1, 16, 128, 1024, 10000} configurations of a robot (Panda by default), measured in
the same run on one core:

* ``drake``: the per-configuration loop a user would write with pydrake —
  ``SetPositions`` + ``CalcRelativeTransform`` + ``CalcJacobianSpatialVelocity``;
* ``numba``: :class:`drake_mh.kinematics.BatchKinematics` (``fk_jacobian``), the library kernel;
* ``numpy``: the same compiled recurrence written with vectorized numpy over N (kept here only
  to justify the choice of numba by measurement);
* ``fk-only``: ``BatchKinematics.fk`` alone, for the FK-per-second target.

Targets: >= 30x Drake's loop at N = 128 and >= 1,000,000 FK per second at
N = 10000. Ratios are computed against the Drake loop measured in the same run.

Run: ``drake-mh study bench_kinematics [--quick]`` or ``python studies/bench_kinematics.py [--quick]``
(the grid lists the robots; the table is printed at the end and put into the report).
"""

from __future__ import annotations

import os
import platform
import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.report.summary import finished, group_by, markdown_table

SIZES = (1, 16, 128, 1024, 10000)


def numpy_fk_jacobian(chain, Q, anchor, R_AE, p_AE):
    """The BatchKinematics recurrence in vectorized numpy over N (reference for the benchmark)."""
    N, F = Q.shape[0], len(chain.parent)
    R = np.empty((F, N, 3, 3))
    p = np.empty((F, N, 3))
    for k in range(F):
        KR, Kp = chain.K[k, :3, :3], chain.K[k, :3, 3]
        a = chain.parent[k]
        if a < 0:
            R[k] = KR
            p[k] = Kp
        else:
            R[k] = (R[a].reshape(N * 3, 3) @ KR).reshape(N, 3, 3)
            p[k] = p[a] + (R[a].reshape(N * 3, 3) @ Kp).reshape(N, 3)
        x = Q[:, chain.qidx[k]]
        if chain.kind[k] == 0:
            c, s = np.cos(x)[:, None], np.sin(x)[:, None]
            r0, r1 = R[k, :, :, 0].copy(), R[k, :, :, 1].copy()
            R[k, :, :, 0] = r0 * c + r1 * s
            R[k, :, :, 1] = r1 * c - r0 * s
        else:
            p[k] += R[k, :, :, 2] * x[:, None]
    T = np.zeros((N, 4, 4))
    T[:, :3, :3] = (R[anchor].reshape(N * 3, 3) @ R_AE).reshape(N, 3, 3)
    T[:, :3, 3] = p[anchor] + (R[anchor].reshape(N * 3, 3) @ p_AE).reshape(N, 3)
    T[:, 3, 3] = 1.0
    J = np.zeros((N, 6, Q.shape[1]))
    for k in np.flatnonzero(chain.ancestors[anchor]):
        z = R[k, :, :, 2]
        col = chain.qidx[k]
        if chain.kind[k] == 0:
            J[:, :3, col] = z
            J[:, 3:, col] = np.cross(z, T[:, :3, 3] - p[k])
        else:
            J[:, 3:, col] = z
    return T, J


def _best_time(fn, repeats: int, budget_s: float = 1.0) -> float:
    """Smallest wall time of ``fn()`` over ``repeats`` runs (stops early past ``budget_s``)."""
    best = np.inf
    start = time.perf_counter()
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
        if time.perf_counter() - start > budget_s:
            break
    return best


def drake_loop(robot, Q):
    """Per-configuration pydrake loop: pose and Jacobian of the end effector."""
    from pydrake.multibody.tree import JacobianWrtVariable

    plant, ctx, ee, world = robot.plant, robot.plant_context, robot.ee_frame, robot.plant.world_frame()
    zero = np.zeros(3)
    for q in Q:
        plant.SetPositions(ctx, q)
        plant.CalcRelativeTransform(ctx, world, ee)
        plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kQDot, ee, zero, world, world)


def measure(robot_name: str, N: int, rng: np.random.Generator, repeats: int) -> dict:
    """Measure every method at one N (same process, back to back); returns one table row."""
    import drake_mh

    robot = drake_mh.load_robot(robot_name)
    kin = robot.batch
    anchor, R_AE, p_AE, _ = kin.frame_arrays(None)
    kin.fk_jacobian(robot.random_configurations(2, rng))  # compile (numba cache) before timing
    Q = robot.random_configurations(N, rng)
    t_drake = _best_time(lambda: drake_loop(robot, Q), max(3, repeats // 4) if N < 1000 else 2)
    t_numba = _best_time(lambda: kin.fk_jacobian(Q), repeats)
    t_numpy = _best_time(lambda: numpy_fk_jacobian(kin.chain, Q, anchor, R_AE, p_AE), repeats)
    t_fk = _best_time(lambda: kin.fk(Q), repeats)
    return dict(
        robot=robot_name, N=N,
        drake_us=1e6 * t_drake / N, numba_us=1e6 * t_numba / N, numpy_us=1e6 * t_numpy / N,
        fk_only_us=1e6 * t_fk / N,
        ratio_numba=t_drake / t_numba, ratio_numpy=t_drake / t_numpy,
        fk_per_s=N / t_fk,
    )


def run_case(case: Case) -> dict:
    """One study case: all methods at one robot and N (fewer repeats in quick mode)."""
    row = measure(case["robot"], case["N"], case.instance_rng, repeats=5 if case.quick else 20)
    row["time"] = row["numba_us"] * 1e-6  # [s] per configuration, batched FK + Jacobian
    row["machine"] = machine()
    return row


def machine() -> str:
    """One line describing where the benchmark ran."""
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
            f"Python {platform.python_version()}, numpy {np.__version__}")


def summarize(records: list[dict]) -> str:
    """The benchmark's table and target lines, per robot."""
    out = []
    for robot, rows in group_by(finished(records), "robot").items():
        by_n = {r["N"]: r for r in rows}
        out.append(f"{robot}: batched FK + Jacobian vs Drake's per-configuration loop ({rows[0]['machine']})")
        out += markdown_table(
            ["N", "Drake loop [µs/config]", "numba FK+J [µs/config]", "ratio", "numpy FK+J [µs/config]", "ratio",
             "numba FK only: FK/s"],
            [[n, f"{r['drake_us']:.2f}", f"{r['numba_us']:.3f}", f"{r['ratio_numba']:.0f}x", f"{r['numpy_us']:.3f}",
              f"{r['ratio_numpy']:.1f}x", f"{r['fk_per_s']:,.0f}"] for n, r in sorted(by_n.items())])
        if 128 in by_n:
            out.append(f"target >= 30x at N = 128: {by_n[128]['ratio_numba']:.0f}x")
        if 10000 in by_n:
            out.append(f"target >= 1,000,000 FK/s at N = 10000: {by_n[10000]['fk_per_s']:,.0f}")
        out.append("")
    return "\n".join(out).rstrip()


study = Study(
    name="bench_kinematics",
    run=run_case,
    grid={"robot": ["panda"], "N": list(SIZES)},
    quick_grid={"robot": ["panda"], "N": [1, 128, 1024]},
    fields=Fields(method="robot", time="time", rank=False, group_by=("N",)),
    description=(
        "Batched FK + Jacobian (drake_mh.kinematics.BatchKinematics, numba) against Drake's "
        "per-configuration Python loop, a vectorized-numpy version of the same recurrence, and "
        "batched FK alone, for N configurations at once. Times are the best of several repeats "
        "per configuration; ratios are against the Drake loop measured in the same case. Cases "
        "run one at a time (max_workers=1) so that measurements never overlap."
    ),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
