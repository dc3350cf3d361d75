"""The compiled core's exact distances and penetration correction against their numba kernels.

Per case, both implementations run in the same process on the same arrays, interleaved in
rounds (their order alternating), after both are compiled or loaded:

* ``min_only`` and ``all pairs``: one configuration's exact distances
  (:func:`drake_mh.scene.kernels.exact.exact_pairs` against a call of ``_native.ExactPairs``
  holding the same arrays, as :class:`drake_mh.scene.exact.ExactDistances` calls them; smallest-only mode as
  ``Scene.min_distance`` and every pair as ``Scene.distances``), one call per configuration
  cycling through 200 random configurations;
* ``correction``: the penetration correction of 200 configurations with every value negative
  (every (configuration, obstacle) pair corrected, as ``Scene.batch_min_distance`` does for the
  configurations where a sphere penetrates):
  ``drake_mh.scene.penetration._correct_clearances`` against ``_native.correct_clearances``.

Scenes: :func:`drake_mh.scene.benchmark.benchmark_scene` ``"1 sphere"``, ``"10 mixed"`` and
``"10 mixed as meshes"`` (their convex pieces: the certified GJK) of the capsule Panda and the
Panda with its hand. Reported: µs per configuration (median of rounds, wall and process CPU
time), the ratio native / numba (below 1: the compiled core is faster) of the medians and of
the CPU times, the 1-minute load average, and the largest difference of the distances.
Results: docs/native.md.

Run: ``drake-mh study native_exact_speed [--quick]`` or ``python studies/native_exact_speed.py [--quick]``.
"""

from __future__ import annotations

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, interleaved, load_average
from drake_mh.study.report.summary import cell, cpu_and_load, finished, markdown_table

ROBOTS = ("panda", "panda_hand")  # the bundled capsule Panda; drake_mh.robot.examples' mesh Panda
SCENES = ("1 sphere", "10 mixed", "10 mixed as meshes")
CASES = ("min_only", "all pairs", "correction")
ROUNDS, QUICK_ROUNDS = 9, 3
CONFIGURATIONS = 200


def _robot(name: str):
    import drake_mh
    from drake_mh.robot.examples import load_example_arm

    return drake_mh.load_robot(name) if name == ROBOTS[0] else load_example_arm(name)


def _exact(scene, native, Q, min_only: bool, rounds: int) -> tuple[dict, float]:
    from drake_mh.scene.kernels import exact as X
    from drake_mh.scene.kernels import gjk

    scene.min_distance(Q[0])
    exact = scene._exact
    state = exact.state()

    def bound(function):
        outputs = (np.zeros_like(exact.R_WG), np.zeros_like(exact.p_WG), np.zeros_like(state.out),
                   np.zeros_like(state.status), np.zeros_like(state.need), np.zeros_like(state.order))
        return lambda i: function(Q[i], *exact._chain, exact.g_int, exact.g_float, state.vertices, state.o_int,
                                  state.o_float, exact.self_pairs, np.inf, min_only, gjk.TOLERANCE, *outputs)[0]

    numba = bound(X.exact_pairs)
    pairs = native.ExactPairs(*exact._chain, exact.g_int, exact.g_float, state.vertices, state.o_int, state.o_float,
                              exact.self_pairs, gjk.TOLERANCE, np.zeros_like(exact.R_WG), np.zeros_like(exact.p_WG),
                              np.zeros_like(state.out), np.zeros_like(state.status), np.zeros_like(state.need),
                              np.zeros_like(state.order))

    def compiled(i):
        return pairs(Q[i], np.inf, min_only)[0]

    worst = max(abs(numba(i) - compiled(i)) for i in range(len(Q)))
    times = interleaved({"numba": numba, "native": compiled}, range(len(Q)), len(Q), rounds)
    return {name: (wall, cpu) for name, (wall, _, cpu) in times.items()}, worst


def _correction(scene, native, Q, rounds: int) -> tuple[dict, float]:
    from drake_mh.scene import penetration

    points = scene.robot.batch.points(Q, *scene._compiled_cores)
    arrays = (*scene._core_arrays, *scene.obstacle_arrays[:3], scene.obstacle_arrays[4], *scene._obstacle_polytopes)
    values = np.full((len(Q), len(scene.obstacle_owners)), -1.0)

    def bound(function):
        def run(_):
            out = values.copy()
            function(out, points, *arrays)
            return out
        return run

    numba, compiled = bound(penetration._correct_clearances), bound(native.correct_clearances)
    a, b = numba(0), compiled(0)
    finite = np.isfinite(a)
    worst = float(np.abs(a[finite] - b[finite]).max(initial=0.0)) if np.array_equal(finite, np.isfinite(b)) else np.inf
    times = interleaved({"numba": numba, "native": compiled}, [0], 1, rounds)
    return {name: (wall / len(Q), cpu / len(Q)) for name, (wall, _, cpu) in times.items()}, worst


def run_case(case: Case) -> dict:
    """One implementation pair on one scene: µs per configuration, ratios, largest difference."""
    from drake_mh._support.native import compiled_core
    from drake_mh.scene.benchmark import benchmark_scene

    row = dict(robot=case["robot"], scene=case["scene"], case=case["case"], cpu=cpu_model(),
               load_average=load_average())
    native = compiled_core()
    row["built"] = native is not None
    if not row["built"]:
        return row
    robot = _robot(case["robot"])
    scene = benchmark_scene(robot, case["scene"])
    Q = np.ascontiguousarray(robot.random_configurations(CONFIGURATIONS, 0))
    rounds = QUICK_ROUNDS if case.quick else ROUNDS
    if case["case"] == "correction":
        times, row["difference"] = _correction(scene, native, Q, rounds)
    else:
        times, row["difference"] = _exact(scene, native, Q, case["case"] == "min_only", rounds)
    for name, (wall, cpu) in times.items():
        row[f"{name}_us"], row[f"{name}_cpu_us"] = 1e6 * wall, 1e6 * cpu
    row["ratio"] = row["native_us"] / row["numba_us"]
    row["ratio_cpu"] = row["native_cpu_us"] / row["numba_cpu_us"]
    row["load_after"] = load_average()
    row["time"] = row["native_us"] * 1e-6
    return row


def summarize(records: list[dict]) -> str:
    """Per robot, scene and case: µs per configuration of both, their ratios, the difference."""
    rows = [r for r in finished(records) if r.get("built")]
    if not rows:
        return ("The compiled core drake_mh._native is not built (or DRAKE_MH_COMPILED_CORE=0): nothing measured "
                "(pip install . builds it).")
    lines = ["Exact distances and penetration correction, compiled core (C++) vs numba, same process, interleaved "
             "rounds; µs per configuration (median of rounds); ratio = native / numba (below 1: C++ faster).", ""]
    lines += markdown_table(
        ["robot", "scene", "case", "numba µs", "native µs", "ratio", "numba CPU µs", "native CPU µs", "ratio (CPU)",
         "largest difference [m]", "load"],
        [[r["robot"], r["scene"], r["case"], cell(r["numba_us"], ".3g"), cell(r["native_us"], ".3g"),
          cell(r["ratio"], ".2f"), cell(r["numba_cpu_us"], ".3g"), cell(r["native_cpu_us"], ".3g"),
          cell(r["ratio_cpu"], ".2f"), cell(r["difference"], ".1e"),
          f"{r['load_average']:.1f}-{r['load_after']:.1f}"] for r in rows])
    lines += ["", cpu_and_load(rows, loads=("load_average", "load_after"))]
    return "\n".join(lines)


study = Study(
    name="native_exact_speed",
    run=run_case,
    grid={"robot": list(ROBOTS), "scene": list(SCENES), "case": list(CASES)},
    quick_grid={"robot": [ROBOTS[0]], "scene": ["10 mixed"], "case": list(CASES)},
    fields=Fields(method="case", time="time", rank=False, group_by=("scene",)),
    description=(
        "The compiled core's exact distances (one configuration, smallest only and every pair) and penetration "
        "correction against the numba kernels they port, on the benchmark scenes of two Pandas, same process, "
        "interleaved rounds, CPU time beside wall time. Cases run one at a time (max_workers=1) so that "
        "measurements never overlap."
    ),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
