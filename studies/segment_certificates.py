"""Certified segments on planned paths and the splines through them: configurations, time, soundness.

Per problem (the first ``PROBLEMS`` of each set: MotionBenchMaker's with ``DRAKE_MH_MBM_ARCHIVE``
set, the Panda with its hand; otherwise the generated sets of the capsule Panda), the
``rrt_connect`` path (``retime=False``, seed 0) and ``CHORDS`` chords of toppra's spline through
it (:func:`drake_mh.trajectories.paths.joint_path`) are certified by the scene's certified
segments (``CollisionModel.compiled_clearances(...).certify_segments``, one call per level, as
the verification calls them) at three levels: the problem's clearance, 4 mm above it, and the
problem's clearance with a 1 mm tolerance (the reported clearance's refinement).

Recorded per set: segments certified, configurations evaluated, milliseconds in the calls, and the
smallest gap between the sphere model's exact clearance at ``DENSE`` configurations of each
certified segment and its certified lower bound (a bound is sound where the gap is >= 0). The
configurations and times compare two checkouts of the segment kernels: run the study in each.

Run: ``drake-mh study segment_certificates`` or ``python studies/segment_certificates.py``.
"""

from __future__ import annotations

import os
import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cpu_and_load, finished, markdown_table

PROBLEMS = 2
CHORDS = 59
DENSE = 1001
LEVELS = ((0.0, np.inf), (0.004, np.inf), (0.0, 1e-3))
"""(added clearance [m], tolerance [m]) of the three certificates."""
GENERATED = ("bookshelf_small", "table_pick", "cage")
SET_SEED = 2024


def _sets() -> list[str]:
    archive = os.environ.get("DRAKE_MH_MBM_ARCHIVE")
    if archive and os.path.exists(archive):
        from drake_mh.planning.problems import MBM_SETS

        return [f"mbm/{name}" for name in MBM_SETS]
    return list(GENERATED)


def _problems(name: str) -> list:
    from drake_mh.planning.problems import motionbenchmaker_set, problem_set

    if name.startswith("mbm/"):
        return motionbenchmaker_set(os.environ["DRAKE_MH_MBM_ARCHIVE"], name[4:], robot="panda_hand_mbm",
                                    count=PROBLEMS)[:PROBLEMS]
    return problem_set(name, "panda", count=PROBLEMS, seed=SET_SEED)[:PROBLEMS]


def run(case: Case) -> dict:
    """Every certificate of one set's problems (module docstring)."""
    from drake_mh.planning import solve_motion
    from drake_mh.scene.kernels.collision import PER_LINK
    from drake_mh.scene.segments import MIN_PIECE, MAX_EVALUATIONS
    from drake_mh.trajectories.paths import joint_path

    row = dict(set=case["set"], cpu=cpu_model(), load_average=load_average(), certified=0, segments=0,
               evaluations=0, seconds=0.0, gap=np.inf)
    t = np.linspace(0.0, 1.0, DENSE)
    for problem in _problems(case["set"]):
        path = solve_motion(problem, "rrt_connect", seed=0, timeout=10.0, retime=False).path
        if path is None or len(path) < 2:
            continue
        spline, _ = joint_path(path, problem.robot, "toppra")
        scene = problem.scene
        model, obstacles = scene.collision_model, scene.obstacle_arrays
        compiled = model.compiled_clearances(obstacles, pairs=True)
        if compiled is None:
            row["built"] = False
            return row
        still = np.zeros_like(obstacles[3])
        G = model.num_links
        for Q in (path, spline(np.linspace(spline.x[0], spline.x[-1], CHORDS + 1))):
            QA, QB = np.ascontiguousarray(Q[:-1]), np.ascontiguousarray(Q[1:])
            for extra, tolerance in LEVELS:
                start = time.perf_counter()
                status, _, lower, _, evaluations = compiled.certify_segments(
                    QA, QB, model.reach, still, 0.0, problem.clearance + extra, problem.self_clearance, tolerance,
                    MIN_PIECE, MAX_EVALUATIONS)
                row["seconds"] += time.perf_counter() - start
                row["segments"] += len(status)
                row["evaluations"] += int(np.sum(evaluations))
                for i in np.flatnonzero(status == 1):
                    row["certified"] += 1
                    dense = np.ascontiguousarray(QA[i] + t[:, None] * (QB[i] - QA[i]))
                    exact = compiled.values(dense, np.zeros(0), np.inf, np.full(model.num_pairs, -np.inf), PER_LINK,
                                            still)
                    row["gap"] = min(row["gap"], float(np.min(exact[:, :G])) - float(lower[i]))
    row.update(built=True, time=row["seconds"], load_after=load_average())
    return row


def summarize(records: list[dict]) -> str:
    rows = [r for r in finished(records) if r.get("built")]
    if not rows:
        return "Nothing measured: the compiled core drake_mh._native is not built (or DRAKE_MH_COMPILED_CORE=0)."
    table = [[r["set"], f"{r['certified']}/{r['segments']}", r["evaluations"], f"{1e3 * r['seconds']:.1f}",
              f"{r['gap']:.2e}"] for r in rows]
    table.append(["all", f"{sum(r['certified'] for r in rows)}/{sum(r['segments'] for r in rows)}",
                  sum(r["evaluations"] for r in rows), f"{1e3 * sum(r['seconds'] for r in rows):.1f}",
                  f"{min(r['gap'] for r in rows):.2e}"])
    lines = [f"Certified segments of {PROBLEMS} paths per set and {CHORDS} chords of the spline through each, at the "
             "clearance, 4 mm above it and with a 1 mm tolerance; gap = exact sphere-model clearance at "
             f"{DENSE} configurations of a certified segment less its bound (>= 0: sound).", ""]
    lines += markdown_table(["set", "certified / segments", "configurations", "ms", "smallest gap [m]"], table)
    lines += ["", cpu_and_load(rows, loads=("load_average", "load_after"))]
    return "\n".join(lines)


study = Study(
    name="segment_certificates",
    run=run,
    grid={"set": _sets()},
    quick_grid={"set": _sets()[:1]},
    fields=Fields(method="set", time="time", rank=False),
    description=("Certified segments on planned paths and the splines through them: segments certified, "
                 "configurations evaluated, time, and the smallest gap to exact dense values (soundness)."),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
