"""Collision checking at planning speed: batched boolean and clearance queries, certified segments.

Per robot and scene, methods interleaved in rounds on the same configurations (the robot is
loaded and every kernel compiled before any clock starts):

* ``collision_free`` — :meth:`drake_mh.scene.Scene.collision_free` (compiled sphere model);
* ``batch_min_distance`` — :meth:`~drake_mh.scene.Scene.batch_min_distance` (same kernels,
  clearance per obstacle, penetration corrected);
* ``previous (numpy)`` — the implementation these replaced: compiled sphere centres, then each
  obstacle's closed-form signed distance in numpy (kept here as a baseline);
* ``Drake HasCollisions`` / ``Drake distance`` — Drake's own boolean query and its signed
  distance query (``ComputeSignedDistancePairwiseClosestPoints``), per configuration, on the
  same scene's SceneGraph context: the exact references;
* ``Scene.min_distance`` — our exact distance (Drake, refined where Drake is optimistic);
* ``certify_segments`` — certified straight segments between free configurations, short
  (joint steps of σ = 0.1 rad) and long (σ = 0.5 rad): µs per segment and configurations
  evaluated.

Batched figures are per configuration at ``N = 1024`` and, from Python, per call at ``N = 1``
(one ``(nq,)`` array: the scalar one-configuration kernel, ``collision_free_one``, through its
compiled entry point), averaged over 2,000 consecutive calls cycling through 200 different
configurations, as a planner's validity callback calls it (the kernel's work depends on how
near the arm is to the obstacles, so one configuration repeated would not be representative).
The batch figure times single calls interleaved with the other methods (cold caches); ``warm``
times 20 consecutive calls on the same configurations, as a planner calls it. Each figure is the median of rounds; CPU time beside wall time; the CPU model and the 1-minute
load average are recorded (shared machines: ratios hold better than absolute times).
Correctness is checked in the same run: every configuration ``collision_free`` accepts is
free by Drake's exact distance (``violations`` must be 0). Results: docs/benchmarks.md.

The scenes (:mod:`drake_mh.scene.benchmark`): one ball, ten mixed primitives, the same ten as
meshes, and as a 50,000-point cloud sampled on their surfaces (no Drake rows there: Drake has
no point-cloud shape).

Run: ``drake-mh study collision_speed [--quick]`` or ``python studies/collision_speed.py [--quick]``.
"""

from __future__ import annotations

import math

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average, timed
from drake_mh.study.report.summary import cell, cpu_and_load, finished, markdown_table

ROBOTS = ("panda (bundled, capsules)", "panda_hand")  # then drake_mh.robot.examples
SCENES = ("1 sphere", "10 mixed", "10 mixed as meshes", "10 mixed as a point cloud")  # drake_mh.scene.benchmark
N_BATCH, N_EXACT, N_SEGMENTS, N_ONE, ONE_CALLS = 1024, 50, 200, 200, 2000
"""``N_ONE`` configurations cycled through by the ``ONE_CALLS`` calls of an ``N = 1`` sample."""
WARM_CALLS = 20
"""consecutive calls on the same configurations in a sample of ``collision_free warm``."""


def _robot(name: str):
    import drake_mh
    from drake_mh.robot.examples import load_example_arm

    return drake_mh.load_robot("panda") if name == ROBOTS[0] else load_example_arm(name)


def _scene(robot, kind: str):
    """The shared benchmark scene (:func:`drake_mh.scene.benchmark.benchmark_scene`)."""
    from drake_mh.scene.benchmark import benchmark_scene

    return benchmark_scene(robot, kind)


def _previous(scene, Q):
    """The numpy clearance these kernels replaced (sphere centres compiled, distances in numpy)."""
    centres = scene.sphere_centres(Q)
    radii = scene.sphere_model.radii
    out = np.full(len(Q), np.inf)
    for obstacle in scene.obstacles.values():
        R, p = obstacle.X_WO[:3, :3], obstacle.X_WO[:3, 3]
        out = np.minimum(out, (obstacle.shape.signed_distance((centres - p) @ R) - radii).min(axis=1))
    return out


def _drake(scene, boolean: bool):
    """Drake's own query on a plain context with the same robot and obstacles
    (:func:`drake_mh.scene.exact.drake_reference`: the scene's own context leaves the pairs our
    kernels compute out of Drake's query), for one configuration."""
    from drake_mh.scene.exact import drake_reference

    reference = drake_reference(scene)
    plant, context = scene.robot.plant, reference.plant_context
    port, sg_context = scene.robot.scene_graph.get_query_output_port(), reference.sg_context

    def query(q):
        plant.SetPositions(context, q)
        result = port.Eval(sg_context)
        return result.HasCollisions() if boolean else result.ComputeSignedDistancePairwiseClosestPoints()

    return query


def run(case: Case) -> dict:
    """Time every query on one robot and scene, interleaved."""
    robot = _robot(case["robot"])
    rng = case.rng
    scene = _scene(robot, case["scene"])
    n_batch = 256 if case.quick else N_BATCH
    n_exact = 10 if case.quick else N_EXACT
    n_segments = 20 if case.quick else N_SEGMENTS
    Q = robot.random_configurations(n_batch, rng=rng)
    one_rows = [Q[i % N_ONE] for i in range(ONE_CALLS)]  # N = 1: ONE_CALLS calls cycling through N_ONE rows
    exact_Q = Q[:n_exact]
    free_Q = Q[scene.collision_free(Q)]
    segments = {}
    for label, sigma in (("short", 0.1), ("long", 0.5)):
        QA = free_Q[:n_segments]
        QB = np.clip(QA + rng.normal(0.0, sigma, QA.shape), robot.lower, robot.upper)
        segments[label] = (QA, QB)
    drake_bool, drake_distance = _drake(scene, True), _drake(scene, False)
    cloud = case["scene"].endswith("point cloud")  # Drake has no point-cloud shape: no Drake rows
    methods = {
        "collision_free": (lambda: scene.collision_free(Q), n_batch),
        "collision_free warm": (lambda: scene.collision_free(Q), n_batch),
        "collision_free N=1": (lambda: [scene.collision_free(q) for q in one_rows], ONE_CALLS),
        "batch_min_distance": (lambda: scene.batch_min_distance(Q), n_batch),
        "batch_min_distance N=1": (lambda: [scene.batch_min_distance(q[None]) for q in one_rows], ONE_CALLS),
        "previous (numpy)": (lambda: _previous(scene, Q), n_batch),
        "Drake HasCollisions": (lambda: [drake_bool(q) for q in exact_Q], n_exact),
        "Drake distance": (lambda: [drake_distance(q) for q in exact_Q], n_exact),
        "Scene.min_distance": (lambda: [scene.min_distance(q) for q in exact_Q], n_exact),
    }
    for label, (QA, QB) in segments.items():
        methods[f"certify_segments {label}"] = ((lambda QA=QA, QB=QB: scene.certify_segments(QA, QB)), len(QA))
    if cloud:
        del methods["Drake HasCollisions"], methods["Drake distance"]
    for function, _ in methods.values():  # compile / load everything first
        function()
    rounds = 3 if case.quick else 9
    samples = {name: [] for name in methods}
    for _ in range(rounds):  # interleaved: each method once per round
        for name, (function, count) in methods.items():
            calls = WARM_CALLS if name.endswith("warm") else 1  # "warm": consecutive calls (a planner's use)
            wall, cpu = timed(lambda: [function() for _ in range(calls)], 1)
            samples[name].append((wall / (count * calls), cpu / (count * calls)))
    per_call = {name: (float(np.median([w for w, _ in v])), float(np.median([c for _, c in v])))
                for name, v in samples.items()}
    for name in ("Drake HasCollisions", "Drake distance"):
        per_call.setdefault(name, (float("nan"), float("nan")))
    free = scene.collision_free(exact_Q)
    exact = scene.exact_min_distance(exact_Q)
    certs = {label: scene.certify_segments(QA, QB) for label, (QA, QB) in segments.items()}
    out = {
        "success": True,
        "time": per_call["collision_free"][0],
        "error": float(np.sum(free & (exact < 0))),
        "violations": int(np.sum(free & (exact < 0))),
        "spheres": scene.sphere_model.num_spheres,
        "colliding": float(1.0 - np.mean(scene.collision_free(Q))),
        "cpu": cpu_model(),
        "load_average": load_average(),
    }
    for name, (wall, cpu) in per_call.items():
        out[f"{name} [s]"] = wall
        out[f"{name} cpu [s]"] = cpu
    for label, cert in certs.items():
        out[f"segments {label} certified"] = float(np.mean(cert.certified))
        out[f"segments {label} evaluations"] = float(np.median(cert.evaluations))
    return out


def _us(r, name):
    return r[f"{name} [s]"] * 1e6


def summarize(records: list[dict]) -> str:
    """Per robot and scene: ns per configuration, and ratios to Drake and to the previous code."""
    ok = sorted(finished(records), key=lambda r: (ROBOTS.index(r["robot"]), SCENES.index(r["scene"])))
    if not ok:
        return "no finished case"
    lines = [cpu_and_load(ok), ""] + markdown_table(
        ["robot", "scene", "spheres", "collision_free [ns/config] (CPU)", "warm, 20 calls [ns/config]", "N=1 [µs/call]",
         "batch_min_distance [ns/config]", "N=1 [µs]", "previous numpy [ns/config]", "Drake HasCollisions [µs]",
         "Drake distance [µs]", "Scene.min_distance [µs]", "Drake bool / ours", "previous / ours", "violations"],
        [[r["robot"], r["scene"], r["spheres"],
          f"{_us(r, 'collision_free') * 1e3:.0f} ({r['collision_free cpu [s]'] * 1e9:.0f})",
          cell(r.get("collision_free warm [s]", math.nan) * 1e9, ".0f"),  # "-": records from before the warm figure
          f"{_us(r, 'collision_free N=1'):.2f}", f"{_us(r, 'batch_min_distance') * 1e3:.0f}",
          f"{_us(r, 'batch_min_distance N=1'):.2f}", f"{_us(r, 'previous (numpy)') * 1e3:.0f}",
          f"{_us(r, 'Drake HasCollisions'):.1f}", f"{_us(r, 'Drake distance'):.1f}", f"{_us(r, 'Scene.min_distance'):.1f}",
          f"{_us(r, 'Drake HasCollisions') / _us(r, 'collision_free'):.0f}x",
          f"{_us(r, 'previous (numpy)') / _us(r, 'collision_free'):.0f}x", r["violations"]] for r in ok])
    lines += ["", "Certified segments between free configurations (σ = joint step):", ""] + markdown_table(
        ["robot", "scene", "short σ=0.1: µs/segment", "certified", "configs evaluated (median)",
         "long σ=0.5: µs/segment", "certified", "configs evaluated (median)"],
        [[r["robot"], r["scene"], f"{_us(r, 'certify_segments short'):.1f}", f"{r['segments short certified']:.0%}",
          f"{r['segments short evaluations']:.0f}", f"{_us(r, 'certify_segments long'):.1f}",
          f"{r['segments long certified']:.0%}", f"{r['segments long evaluations']:.0f}"] for r in ok])
    return "\n".join(lines)


study = Study(
    name="collision_speed",
    run=run,
    grid={"robot": list(ROBOTS), "scene": list(SCENES)},
    quick_grid={"robot": [ROBOTS[0]], "scene": [SCENES[1]]},
    fields=Fields(method="robot", success="success", time="time", error="error", nfe="spheres", rank=False,
                  error_unit="configurations"),
    description=(
        "Batched collision queries on the sphere model (boolean and clearance) against Drake's exact "
        "queries and the previous numpy code, in the same run; certified segment cost. 'time' is "
        "collision_free's seconds per configuration at N = 1024, 'error' the configurations it "
        "accepted that Drake's exact distance finds in collision (must be 0)."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
