"""The compiled core (C++, ``drake_mh._native``) against the numba kernels it ports, at runtime.

Per case, both implementations run in the same process on the same configurations, interleaved
in rounds (their order alternating), after every kernel is compiled or loaded:

* ``check`` on a scene of the capsule Panda (47 spheres) and of the Panda with its hand (meshes,
  778 spheres): :func:`drake_mh.scene.benchmark.benchmark_scene` ``"1 sphere"``, ``"10 mixed"``,
  the same as meshes and as a point cloud, and the ten mixed primitives with the robot's
  self-collision pairs; numba's bound batched check
  (:meth:`drake_mh.scene.batch.CollisionModel.free_function`, what
  :meth:`~drake_mh.scene.Scene.collision_free` calls with ``DRAKE_MH_COMPILED_CORE=0``) against
  ``CollisionChecker.free`` (what it calls where the core is built); at ``N = 1`` numba's
  one-configuration entry point (``make_one``, the scene's one-configuration path) against
  ``CollisionChecker.free_one``, 2,000 calls cycling through 200 configurations;
* ``fk`` and ``fk+J``: the end effector's pose (and Jacobian) of ``N`` configurations, numba's
  :func:`drake_mh.kinematics.kernels.fk_jacobian` with its transposition and allocations (as
  :class:`drake_mh.kinematics.BatchKinematics` calls it) against ``Kinematics.fk_jacobian``.

Reported: ns per configuration (median of rounds, wall and process CPU time), the ratio
native / numba (below 1: the compiled core is faster) of the medians, of the least wall times
(the rounds least disturbed by other work) and of the CPU times, the 1-minute load average,
and whether every answer was identical (booleans) or within 1e-12 (poses). CPU ratios hold
better than wall ratios on a shared machine. Without the compiled module (not built) a case
records only that.
Results: docs/native.md.

Run: ``drake-mh study native_speed [--quick]`` or ``python studies/native_speed.py [--quick]``.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cell, cpu_and_load, finished, markdown_table

ROBOTS = ("panda", "panda_hand")  # the bundled capsule Panda (47 spheres); drake_mh.robot.examples' mesh Panda (778)
SCENES = ("1 sphere", "10 mixed", "10 mixed + self", "10 mixed as meshes", "10 mixed as a point cloud")
CASES = SCENES + ("fk", "fk+J")
SIZES = (1, 64, 1024)
ROUNDS, QUICK_ROUNDS = 11, 3
BATCHES = 20
"""Different ``(N, nq)`` batches cycled through by a sample's calls (``N > 1``)."""
ONE_CONFIGURATIONS, ONE_CALLS = 200, 2000


def _robot(name: str):
    import drake_mh
    from drake_mh.robot.examples import load_example_arm

    return drake_mh.load_robot(name) if name == ROBOTS[0] else load_example_arm(name)


def _scene(robot, name: str):
    """A benchmark scene, or its ten mixed primitives with the robot's self-collision pairs."""
    from pydrake.math import RollPitchYaw, RotationMatrix

    from drake_mh.scene import Scene
    from drake_mh.scene.benchmark import benchmark_scene

    if name != "10 mixed + self":
        return benchmark_scene(robot, name)
    scene = Scene(robot, self_collision=True)
    for key, obstacle in benchmark_scene(robot, SCENES[1]).obstacles.items():
        X = obstacle.X_WO
        scene.add(key, obstacle.shape, X[:3, 3], rpy=RollPitchYaw(RotationMatrix(X[:3, :3])).vector())
    return scene


def _interleaved(functions: dict, inputs: list, calls: int, rounds: int) -> dict:
    """``{name: (wall s, least wall s, CPU s)}`` per call: medians (and the least wall time) over
    rounds of ``calls`` calls cycling through ``inputs``, the functions' order alternating from
    round to round."""
    names, samples = list(functions), {name: ([], []) for name in functions}
    for r in range(rounds):
        for name in names if r % 2 == 0 else names[::-1]:
            function = functions[name]
            wall, cpu = time.perf_counter(), time.process_time()
            for i in range(calls):
                function(inputs[i % len(inputs)])
            samples[name][0].append((time.perf_counter() - wall) / calls)
            samples[name][1].append((time.process_time() - cpu) / calls)
    return {name: (float(np.median(w)), float(np.min(w)), float(np.median(c))) for name, (w, c) in samples.items()}


def _check(robot, native, name: str, Qs: list, rounds: int) -> tuple[dict, bool]:
    scene = _scene(robot, name)
    model = scene.collision_model
    ints, floats = model.packed(scene.obstacle_arrays, model.pair_arrays)
    batch = model.free_function(scene.obstacle_arrays)
    checker = native.CollisionChecker(ints, floats)
    if Qs[0].shape[0] == 1:
        entry, buffer = batch.make_one()
        qs = [Q[0] for Q in Qs]
        one = checker.free_one
        identical = all(entry(q, 0.0, 0.0, buffer) == one(q, 0.0, 0.0) for q in qs)
        times = _interleaved({"numba": lambda q: entry(q, 0.0, 0.0, buffer), "native": lambda q: one(q, 0.0, 0.0)},
                             qs, ONE_CALLS, rounds)
        return times, identical
    tiny, free = 1e-12, checker.free  # the clearance Scene.collision_free passes for 0
    identical = all(np.array_equal(batch(Q, tiny, tiny), free(Q, tiny, tiny)) for Q in Qs)
    times = _interleaved({"numba": lambda Q: batch(Q, tiny, tiny), "native": lambda Q: free(Q, tiny, tiny)},
                         Qs, max(1, 12800 // Qs[0].shape[0]), rounds)
    return times, identical


def _kinematics(robot, native, want_jac: bool, Qs: list, rounds: int) -> tuple[dict, bool]:
    from drake_mh.kinematics import kernels

    bk = robot.batch
    parent, KR, Kp, perm, kind, qidx = args = bk.chain_arrays
    kin = native.Kinematics(np.concatenate([parent, perm.ravel(), kind, qidx]).astype(np.int64),
                            np.concatenate([KR.ravel(), Kp.ravel()]))
    anchor, ER, Ep, on_path = bk.frame_arrays(None)
    ER_flat, nq = np.ascontiguousarray(ER.ravel()), robot.nq

    def numba(Q):
        N = Q.shape[0]
        T, J = np.empty((N, 4, 4)), np.empty((N, 6, nq) if want_jac else (0, 6, nq))
        kernels.fk_jacobian(np.ascontiguousarray(Q.T), *args, anchor, ER, Ep, on_path, want_jac, T, J)
        return T, J

    def compiled(Q):
        return kin.fk_jacobian(Q, anchor, ER_flat, Ep, on_path, want_jac)

    identical = all(np.allclose(numba(Q)[0], compiled(Q)[0], rtol=0.0, atol=1e-12) for Q in Qs)
    calls = ONE_CALLS if Qs[0].shape[0] == 1 else max(1, 12800 // Qs[0].shape[0])
    return _interleaved({"numba": numba, "native": compiled}, Qs, calls, rounds), identical


def run_case(case: Case) -> dict:
    """One implementation pair at one ``N``: ns per configuration, ratios, identical answers."""
    row = dict(robot=case["robot"], case=case["case"], N=case["N"], cpu=cpu_model(), load_average=load_average())
    from drake_mh.scene.compiled_check import compiled_core

    _native = compiled_core()
    row["built"] = _native is not None
    if not row["built"]:
        return row

    robot = _robot(case["robot"])
    rng = np.random.default_rng(0)
    N = case["N"]
    Qs = [np.ascontiguousarray(rng.uniform(robot.lower, robot.upper, (N, robot.nq)))
          for _ in range(ONE_CONFIGURATIONS if N == 1 else BATCHES)]
    rounds = QUICK_ROUNDS if case.quick else ROUNDS
    if case["case"] in SCENES:
        times, row["identical"] = _check(robot, _native, case["case"], Qs, rounds)
    else:
        times, row["identical"] = _kinematics(robot, _native, case["case"] == "fk+J", Qs, rounds)
    for name, (wall, least, cpu) in times.items():
        row[f"{name}_ns"], row[f"{name}_least_ns"], row[f"{name}_cpu_ns"] = 1e9 * wall / N, 1e9 * least / N, 1e9 * cpu / N
    row["ratio"] = row["native_ns"] / row["numba_ns"]
    row["ratio_least"] = row["native_least_ns"] / row["numba_least_ns"]
    row["ratio_cpu"] = row["native_cpu_ns"] / row["numba_cpu_ns"]
    row["load_after"] = load_average()
    row["time"] = row["native_ns"] * 1e-9
    return row


def summarize(records: list[dict]) -> str:
    """Per case and N: ns per configuration of both, their ratios, identical answers."""
    rows = [r for r in finished(records) if r.get("built")]
    if not rows:
        return ("The compiled core drake_mh._native is not built (or DRAKE_MH_COMPILED_CORE=0): nothing measured "
                "(pip install . builds it).")
    lines = ["Compiled core (C++) vs numba, same process, interleaved rounds; ns per configuration (median of "
             "rounds); ratio = native / numba (below 1: C++ faster).", ""]
    lines += markdown_table(
        ["robot", "case", "N", "numba ns", "native ns", "ratio", "ratio (least wall)", "numba CPU ns", "native CPU ns",
         "ratio (CPU)", "identical", "load"],
        [[r["robot"], r["case"], r["N"], cell(r["numba_ns"], ".4g"), cell(r["native_ns"], ".4g"), cell(r["ratio"], ".2f"),
          cell(r["ratio_least"], ".2f"),
          cell(r["numba_cpu_ns"], ".4g"), cell(r["native_cpu_ns"], ".4g"), cell(r["ratio_cpu"], ".2f"),
          r["identical"], f"{r['load_average']:.1f}-{r['load_after']:.1f}"] for r in rows])
    lines += ["", cpu_and_load(rows, loads=("load_average", "load_after"))]
    return "\n".join(lines)


study = Study(
    name="native_speed",
    run=run_case,
    grid={"robot": list(ROBOTS), "case": list(CASES), "N": list(SIZES)},
    quick_grid={"robot": [ROBOTS[0]], "case": ["10 mixed + self", "fk+J"], "N": [64]},
    fields=Fields(method="case", time="time", rank=False, group_by=("N",)),
    description=(
        "The compiled core (C++, drake_mh._native) against the numba kernels it ports: the sphere-model "
        "check on the benchmark scenes (two Pandas) and batched forward kinematics, N = 1, 64, 1024, same process, "
        "interleaved rounds, CPU time beside wall time. Cases run one at a time (max_workers=1) so that "
        "measurements never overlap."
    ),
    summarize=summarize,
    max_workers=1,
)


if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
