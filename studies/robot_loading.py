"""Robot loading: robot descriptions with meshes, first load (mesh conversion) and cached load.

For each arm of ``example-robot-data`` (a test extra; URDFs with ``package://`` STL/DAE
meshes), a case loads the model as shipped with :func:`drake_mh.load_robot` into a fresh,
empty mesh cache (``DRAKE_MH_CACHE`` pointed at a new temporary folder): the *first* load
converts every collision mesh to its convex hull ``.obj`` (and ``.stl`` visuals to ``.obj``);
then the same model is loaded ``CACHED_LOADS`` times more and the median is the *cached*
load. Drake, trimesh and xacro are imported before the clock starts (a warm-up load of
another model), so the times are those of a user's second robot in a session.

Recorded: both times [s], nq, locked joints, collision hulls converted, the CPU model and
the 1-minute load average (the machines are shared: absolute times drift; the ratio holds
better). ``error`` is the cached / first ratio.

Run: ``drake-mh study robot_loading [--quick]`` or ``python studies/robot_loading.py [--quick]``.
"""

from __future__ import annotations

import os
import time

import numpy as np

from drake_mh._support.cache import temporary_cache
from drake_mh.robot.examples import EXAMPLE_ARMS, example_robot_data_root, load_example_arm
from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model
from drake_mh.study.report.summary import cpu_and_load, finished, group_by, markdown_table, median, values

ROBOTS = EXAMPLE_ARMS  # name -> (path inside example-robot-data, end-effector frame)
CACHED_LOADS, QUICK_CACHED_LOADS = 5, 2


def run(case: Case) -> dict:
    """First and cached load of one robot, in a fresh mesh cache."""
    import drake_mh

    root = example_robot_data_root()
    if root is None:
        load_example_arm(case["robot"])  # raises, saying how to install it
    rel, ee = ROBOTS[case["robot"]]
    path = root / rel
    with temporary_cache():  # warm-up: imports (Drake parser, trimesh, pycollada) off the clock
        drake_mh.load_robot(root / ROBOTS["ur5"][0], ee_frame=ROBOTS["ur5"][1])
    with temporary_cache() as cache:
        start = time.perf_counter()
        robot = drake_mh.load_robot(path, ee_frame=ee)
        first = time.perf_counter() - start
        hulls = len(list((cache / "meshes").glob("*_hull.obj")))
        visuals = len(list((cache / "meshes").glob("*_visual.obj")))
        cached = []
        for _ in range(QUICK_CACHED_LOADS if case.quick else CACHED_LOADS):
            start = time.perf_counter()
            drake_mh.load_robot(path, ee_frame=ee)
            cached.append(time.perf_counter() - start)
    cached_median = float(np.median(cached))
    return {
        "success": True,
        "nq": robot.nq,
        "locked": len(robot.locked_joints),
        "hulls": hulls,
        "visual_conversions": visuals,
        "time_first": first,
        "time": cached_median,
        "error": cached_median / first,
        "cpu": cpu_model(),
        "load_average": os.getloadavg()[0],
    }


def summarize(records: list[dict]) -> str:
    """One row per robot: medians over replicates."""
    groups = group_by(finished(records), "robot")
    rows = []
    for name in [n for n in ROBOTS if n in groups]:
        group, g = groups[name], groups[name][0]
        first, cached = median(values(group, "time_first")), median(values(group, "time"))
        rows.append([name, g["nq"], g["locked"], g["hulls"], g["visual_conversions"], f"{first:.3f}", f"{cached:.3f}",
                     f"{cached / first:.2f}"])
    return "\n".join([cpu_and_load(finished(records)), ""] + markdown_table(
        ["robot", "nq", "locked", "hulls", "visual .obj", "first load [s]", "cached load [s]", "cached / first"], rows))


study = Study(
    name="robot_loading",
    run=run,
    grid={"robot": list(ROBOTS), "rep": range(3)},
    quick_grid={"robot": ["panda_hand", "ur5"], "rep": range(1)},
    fields=Fields(method="robot", success="success", time="time", error="error", nfe="hulls", rank=False,
                  error_unit=""),
    description=(
        "Loading robot descriptions with meshes as shipped (example-robot-data): first load into an "
        "empty mesh cache (collision meshes converted to convex hulls) and the median cached load. "
        "'time' is the cached load [s], 'error' the cached / first ratio."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
