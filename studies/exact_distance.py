"""Exact distance overhead: ``Scene.min_distance`` and ``Scene.distances`` against Drake's own query.

Per robot and scene, three methods interleaved in rounds on the same configurations (robot
loaded, kernels compiled, every method called once before any clock starts):

* ``Drake query`` — what a Drake user writes: ``SetPositions`` + ``Eval`` +
  ``ComputeSignedDistancePairwiseClosestPoints`` on a context holding the same robot and
  obstacles (:func:`drake_mh.scene.exact.drake_reference`; capsule-capsule pairs filtered out,
  because Drake 1.51's query hangs on them);
* ``Scene.min_distance`` — our exact minimum (:mod:`drake_mh.scene.exact`);
* ``Scene.distances`` — every pair as :class:`drake_mh.scene.DistancePair` objects, sorted.

A sample is one pass over ``N`` configurations (each answer dropped before the next call: kept,
200 lists of 170 pairs made Python's cyclic garbage collector dominate ``distances``, 3x); each figure is the median over rounds of wall
and CPU time per call, beside the CPU model and the 1-minute load average (shared machines:
ratios hold better than absolute times). Correctness in the same run, on every configuration:
``min_distance`` equals the smallest of ``distances`` (``mismatch``), and per (link, obstacle)
pair that both compute ours is never more than Drake's (``above_drake``, must be <= 1e-9 m);
``drake_optimism`` is the most clearance Drake reported above ours on such a pair (its GJK).
Scenes: one ball in front of the arm, and ten mixed obstacles (spheres, boxes, cylinders,
capsules, drawn once from seed 1 in the arm's workspace; some configurations collide).

Run: ``drake-mh study exact_distance [--quick]`` or ``python studies/exact_distance.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cpu_and_load, finished, markdown_table

ROBOTS = ("panda (bundled, capsules)", "panda_hand", "ur5")  # then drake_mh.robot.examples (meshes)
SCENES = ("1 sphere", "10 mixed")  # drake_mh.scene.benchmark.BENCHMARK_SCENES
METHODS = ("Drake query", "Scene.min_distance", "Scene.distances")
N_CONFIGS, ROUNDS = 200, 9


def _robot(name: str):
    import drake_mh
    from drake_mh.robot.examples import load_example_arm

    return drake_mh.load_robot("panda") if name == ROBOTS[0] else load_example_arm(name)


def _scene(robot, kind: str):
    """The shared benchmark scene (:func:`drake_mh.scene.benchmark.benchmark_scene`)."""
    from drake_mh.scene.benchmark import benchmark_scene

    return benchmark_scene(robot, kind)


def run(case: Case) -> dict:
    """Time Drake's query, ``min_distance`` and ``distances`` on one robot and scene, interleaved."""
    from drake_mh.scene.exact import drake_reference

    robot = _robot(case["robot"])
    scene = _scene(robot, case["scene"])
    drake = drake_reference(scene)
    Q = robot.random_configurations(40 if case.quick else N_CONFIGS, rng=case.rng)
    def each(function):  # one call per configuration, the answer dropped (not 200 lists kept alive)
        def loop():
            for q in Q:
                function(q)
        return loop

    methods = {METHODS[0]: each(drake), METHODS[1]: each(scene.min_distance), METHODS[2]: each(scene.distances)}
    for function in methods.values():  # compile / load everything first
        function()
    load_start = load_average()
    samples = {name: [] for name in methods}
    for _ in range(3 if case.quick else ROUNDS):  # interleaved: each method once per round
        for name, function in methods.items():
            wall, cpu = time.perf_counter(), time.process_time()
            function()
            samples[name].append(((time.perf_counter() - wall) / len(Q), (time.process_time() - cpu) / len(Q)))
    load = load_average()
    ours = np.array([scene.min_distance(q) for q in Q])
    pairs = [scene.distances(q) for q in Q]
    smallest = np.array([p[0].distance if p else np.inf for p in pairs])
    robot_links = set(robot.link_names())
    above, optimism = [], []
    for q, ours_pairs in zip(Q, pairs):  # per (link, obstacle) pair that both compute
        mine, theirs = {}, {}
        for p in ours_pairs:
            mine[p.link, p.other] = min(mine.get((p.link, p.other), np.inf), p.distance)
        for p in drake(q):
            key = tuple(sorted((drake.names[p.id_A], drake.names[p.id_B]), key=lambda n: n not in robot_links))
            theirs[key] = min(theirs.get(key, np.inf), p.distance)
        common = [k for k in theirs if k in mine]
        above += [mine[k] - theirs[k] for k in common]
        optimism += [theirs[k] - mine[k] for k in common]
    out = {
        "success": True,
        "mismatch": float(np.max(np.abs(ours - smallest))),
        "above_drake": float(np.max(above, initial=0.0)),
        "drake_optimism": float(np.max(optimism, initial=0.0)),
        "pairs": float(np.mean([len(p) for p in pairs])),
        "drake_pairs": float(np.mean([len(drake(q)) for q in Q])),
        "colliding": float(np.mean(ours < 0)),
        "cpu": cpu_model(),
        "load_average": load,
        "load_start": load_start,
    }
    for name, values in samples.items():
        out[f"{name} [s]"] = float(np.median([w for w, _ in values]))
        out[f"{name} cpu [s]"] = float(np.median([c for _, c in values]))
    out["time"] = out["Scene.min_distance [s]"]
    out["error"] = out["above_drake"]
    return out


def summarize(records: list[dict]) -> str:
    """Per robot and scene: µs per call (wall, CPU), ratios to Drake's query, correctness."""
    ok = sorted(finished(records), key=lambda r: (ROBOTS.index(r["robot"]), SCENES.index(r["scene"])))
    if not ok:
        return "no finished case"

    def us(r, name):
        return r[f"{name} [s]"] * 1e6, r[f"{name} cpu [s]"] * 1e6

    rows = []
    for r in ok:
        (dw, dc), (mw, mc), (aw, ac) = (us(r, m) for m in METHODS)
        rows.append([r["robot"], r["scene"], f"{r['pairs']:.0f} ({r['drake_pairs']:.0f})", f"{dw:.1f} / {dc:.1f}",
                     f"{mw:.1f} / {mc:.1f}", f"{mc / dc:.2f}", f"{aw:.1f} / {ac:.1f}", f"{ac / dc:.2f}",
                     f"{r['colliding']:.0%}", f"{r['above_drake']:.1e}", f"{r['drake_optimism'] * 1e3:.2f}"])
    return "\n".join(
        [f"{cpu_and_load(ok, loads=('load_average', 'load_start'), digits=2)} (before and after the timed rounds); "
         f"min_distance vs smallest of distances: {max(r['mismatch'] for r in ok):.1e} m at most", ""]
        + markdown_table(["robot", "scene", "pairs (Drake's)", "Drake query [µs] wall / CPU",
                          "min_distance [µs] wall / CPU", "ratio to Drake (CPU)", "distances [µs] wall / CPU",
                          "ratio to Drake (CPU)", "in collision", "above Drake [m]", "Drake's optimism [mm]"], rows))


study = Study(
    name="exact_distance",
    run=run,
    grid={"robot": list(ROBOTS), "scene": list(SCENES)},
    quick_grid={"robot": [ROBOTS[0], ROBOTS[1]], "scene": [SCENES[1]]},
    fields=Fields(method="robot", success="success", time="time", error="error", nfe="pairs", rank=False,
                  group_by=("scene",), error_unit="m"),
    description=(
        "Exact distance overhead: Scene.min_distance and Scene.distances against Drake's own "
        "signed-distance query on the same robot and obstacles, interleaved, wall and CPU time. "
        "'time' is min_distance's seconds per call, 'error' how far it was above Drake's minimum "
        "(must be <= 1e-9 m: Drake's GJK is optimistic, never ours)."
    ),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
