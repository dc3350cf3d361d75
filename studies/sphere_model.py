"""Sphere model: build time (first and cached), sphere counts and bounds, batched clearance cost.

For the bundled Panda (capsules) and the mesh arms of ``example-robot-data`` (a test extra),
a case builds :class:`drake_mh.geometry.spheres.SphereModel` at one covering tolerance into a fresh,
empty cache (``DRAKE_MH_CACHE`` pointed at a new temporary folder), then again from that cache,
and times ``Scene.batch_min_distance`` on ``N = 1000`` random configurations against three
obstacles (a ball, a tilted box, a tilted cylinder) placed in the arm's workspace, beside
Drake's exact ``Scene.min_distance`` on 20 of them (same scene, same run). The robot is loaded
and its kernels compiled before any clock starts.

Recorded: both build times [s], spheres in all and per link (min, max), the stated bound [m],
``batch_min_distance`` [µs per configuration] (median of 10 calls), the exact query [µs], the
share of configurations in collision, the CPU model and the 1-minute load average (shared
machines: absolute times drift, ratios hold better). ``time`` is the first build, ``error`` the
bound.

Run: ``drake-mh study sphere_model [--quick]`` or ``python studies/sphere_model.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh._support.cache import temporary_cache
from drake_mh.robot.examples import load_example_arm
from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cpu_and_load, finished, markdown_table

ROBOTS = ("panda (bundled, capsules)", "panda_hand", "ur5", "xarm7", "kinova")  # then drake_mh.robot.examples
N_BATCH, N_EXACT = 1000, 20


def _robot(name: str):
    import drake_mh

    return drake_mh.load_robot("panda") if name == ROBOTS[0] else load_example_arm(name)


def _scene(robot, tolerance: float):
    """Three obstacles in front of the arm, at fixed fractions of its reach."""
    from drake_mh.scene import Box, Cylinder, Scene, Sphere

    reach = float(np.linalg.norm(robot.fk(robot.home)[:3, 3])) or 0.5
    scene = Scene(robot, sphere_tolerance=tolerance)
    scene.add("ball", Sphere(0.08), [0.6 * reach, 0.15, 0.5 * reach])
    scene.add("box", Box((0.2, 0.2, 0.1)), [0.45 * reach, -0.25, 0.3 * reach], rpy=[0.3, 0.2, 0.1])
    scene.add("post", Cylinder(0.04, 0.5), [0.35 * reach, 0.3, 0.4 * reach], rpy=[0.2, 0.0, 0.0])
    return scene


def run(case: Case) -> dict:
    """Build the sphere model of one robot at one tolerance (fresh cache, then cached); time queries."""
    from drake_mh.geometry.spheres import SphereModel

    robot = _robot(case["robot"])
    tolerance = float(case["tolerance"])
    with temporary_cache():
        start = time.perf_counter()
        model = SphereModel.from_robot(robot, tolerance)
        first = time.perf_counter() - start
        start = time.perf_counter()
        SphereModel.from_robot(robot, tolerance)
        cached = time.perf_counter() - start
        scene = _scene(robot, tolerance)
        Q = robot.random_configurations(N_BATCH if not case.quick else 200, rng=case.rng)
        d = scene.batch_min_distance(Q)  # compiles / loads the kernels
        times = []
        for _ in range(10):
            start = time.perf_counter()
            scene.batch_min_distance(Q)
            times.append(time.perf_counter() - start)
        start = time.perf_counter()
        for q in Q[:N_EXACT]:
            scene.min_distance(q)
        exact = (time.perf_counter() - start) / N_EXACT
    counts = model.link_counts()
    batch_us = float(np.median(times)) / len(Q) * 1e6
    return {
        "success": True,
        "spheres": model.num_spheres,
        "per_link_min": min(counts.values()),
        "per_link_max": max(counts.values()),
        "bound": float(model.bound),
        "time": first,
        "time_cached": cached,
        "batch_us": batch_us,
        "exact_us": exact * 1e6,
        "colliding": float(np.mean(d < 0)),
        "error": float(model.bound),
        "cpu": cpu_model(),
        "load_average": load_average(),
    }


def summarize(records: list[dict]) -> str:
    """One row per robot and tolerance."""
    ok = sorted(finished(records), key=lambda r: (ROBOTS.index(r["robot"]), r["tolerance"]))
    rows = [[r["robot"], f"{r['tolerance']:g}", r["spheres"], f"{r['per_link_min']}-{r['per_link_max']}",
             f"{r['bound'] * 1e3:.2f}", f"{r['time']:.3f}", f"{r['time_cached']:.4f}", f"{r['batch_us']:.1f}",
             f"{r['exact_us']:.0f}", f"{r['exact_us'] / r['batch_us']:.1f}x", f"{r['colliding']:.0%}"] for r in ok]
    return "\n".join([cpu_and_load(ok), ""] + markdown_table(
        ["robot", "tolerance [m]", "spheres", "per link", "bound [mm]", "first build [s]", "cached [s]",
         "batch [µs/config]", "exact [µs/config]", "exact / batch", "in collision"], rows))


study = Study(
    name="sphere_model",
    run=run,
    grid={"robot": list(ROBOTS), "tolerance": [0.02, 0.01]},
    quick_grid={"robot": ["panda (bundled, capsules)", "ur5"], "tolerance": [0.01]},
    fields=Fields(method="robot", success="success", time="time", error="error", nfe="spheres", rank=False,
                  error_unit="m"),
    description=(
        "Sphere models of capsule and mesh arms: build time into an empty cache and from it, sphere "
        "counts, the stated bound, and the batched clearance query beside Drake's exact one. 'time' "
        "is the first build [s], 'error' the bound [m]."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
