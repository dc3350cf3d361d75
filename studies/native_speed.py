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
* ``clearances`` and ``min clearance``: the sphere model's clearance per obstacle ``(N, K)`` and
  over all obstacles ``(N, 1)`` on the ten mixed primitives (what
  :meth:`~drake_mh.scene.Scene.batch_obstacle_distances` and ``batch_min_distance`` compute):
  :func:`drake_mh.scene.kernels.entry.obstacle_clearances_packed` against ``Clearances.values``;
* ``certify`` and ``certify MBM``: :func:`drake_mh.scene.kernels.segments.certify_segments`
  against ``Clearances.certify_segments`` on ``N`` segments (the ns are per segment; ``N`` at most
  :data:`CERTIFY_MAX`): random
  segments between free configurations (steps of 0.3 rad) among the ten mixed primitives with
  the robot's self-collision pairs, and (with ``DRAKE_MH_MBM_ARCHIVE`` set, else skipped) random
  walks of such steps from the starts of MotionBenchMaker's ``bookshelf_small`` problems (the
  Panda with its hand as those problems were made for, ``panda_hand_mbm``, on the
  ``panda_hand`` rows), each at the clearances 0 and then a 1 mm tolerance (what
  :func:`~drake_mh.scene.segments.certify_path` refines with);
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

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, interleaved, load_average
from drake_mh.study.report.summary import cell, cpu_and_load, finished, markdown_table

ROBOTS = ("panda", "panda_hand")  # the bundled capsule Panda (47 spheres); drake_mh.robot.examples' mesh Panda (778)
SCENES = ("1 sphere", "10 mixed", "10 mixed + self", "10 mixed as meshes", "10 mixed as a point cloud")
CLEARANCES = ("clearances", "min clearance")
CERTIFY = ("certify", "certify MBM")
CASES = SCENES + CLEARANCES + CERTIFY + ("fk", "fk+J")
CERTIFY_MAX = 64
"""Most segments per certify call measured (1024 meshed-Panda segments take about 20 s a call)."""
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
        times = interleaved({"numba": lambda q: entry(q, 0.0, 0.0, buffer), "native": lambda q: one(q, 0.0, 0.0)},
                             qs, ONE_CALLS, rounds)
        return times, identical
    tiny, free = 1e-12, checker.free  # the clearance Scene.collision_free passes for 0
    identical = all(np.array_equal(batch(Q, tiny, tiny), free(Q, tiny, tiny)) for Q in Qs)
    times = interleaved({"numba": lambda Q: batch(Q, tiny, tiny), "native": lambda Q: free(Q, tiny, tiny)},
                         Qs, max(1, 12800 // Qs[0].shape[0]), rounds)
    return times, identical


def _clearances(robot, native, overall: bool, Qs: list, rounds: int) -> tuple[dict, bool]:
    from drake_mh.scene.kernels import collision, entry

    scene = _scene(robot, SCENES[1])
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    ints, floats = model.packed(obstacles, model.no_pair_arrays)
    compiled = native.Clearances(ints, floats)
    mode, width = (collision.OVERALL, 1) if overall else (collision.PER_OBSTACLE, len(obstacles[0]))
    v_WO, none = np.zeros((len(obstacles[0]), 3)), np.zeros(0)

    def numba(Q):
        out = np.empty((Q.shape[0], width))
        entry.obstacle_clearances_packed(Q, mode, ints, floats, v_WO, out)
        return out

    def compiled_values(Q):
        return compiled.values(Q, none, np.inf, none, mode, v_WO)

    identical = all(np.allclose(numba(Q), compiled_values(Q), rtol=0.0, atol=1e-12) for Q in Qs)
    calls = ONE_CALLS if Qs[0].shape[0] == 1 else max(1, 12800 // Qs[0].shape[0])
    return interleaved({"numba": numba, "native": compiled_values}, Qs, calls, rounds), identical


def _segments(robot_name: str, mbm: bool, N: int, batches: int) -> tuple | None:
    """``(scene, [(QA, QB) (N, nq)] * batches)``: segments of steps of 0.3 rad between free
    configurations (random walks from MotionBenchMaker starts with ``mbm``; None without the archive)."""
    import os

    rng = np.random.default_rng(1)
    if not mbm:
        scene = _scene(_robot(robot_name), SCENES[2])
        starts = None
    else:
        path = os.environ.get("DRAKE_MH_MBM_ARCHIVE")
        if not path:
            return None
        from drake_mh.planning.problems import motionbenchmaker_set

        problems = motionbenchmaker_set(path, "bookshelf_small", count=10,
                                        robot="panda_hand_mbm" if robot_name == ROBOTS[1] else "panda")
        scene, starts = problems[0].scene, problems[0].q_start[None]  # (a ProblemSet is a list)
    robot = scene.robot
    batches_out = []
    for _ in range(batches):
        QA = []
        while len(QA) < N:
            if starts is None:
                Q = rng.uniform(robot.lower, robot.upper, (4 * N + 8, robot.nq))
            else:  # a walk from a start: each step to a free configuration
                Q = starts[rng.integers(len(starts), size=4 * N + 8)] + rng.normal(0.0, 0.3, (4 * N + 8, robot.nq))
                Q = np.clip(Q, robot.lower, robot.upper)
            QA.extend(Q[scene.collision_free(Q)])
        QA = np.array(QA[:N])
        QB = np.clip(QA + rng.normal(0.0, 0.3, QA.shape), robot.lower, robot.upper)
        batches_out.append((np.ascontiguousarray(QA), np.ascontiguousarray(QB)))
    return scene, batches_out


def _certify(robot_name: str, native, mbm: bool, N: int, rounds: int) -> tuple[dict, bool] | None:
    from drake_mh.scene.kernels import segments as SK
    from drake_mh.scene.segments import MIN_PIECE, MAX_EVALUATIONS

    made = _segments(robot_name, mbm, N, 4)
    if made is None:
        return None
    scene, pairs = made
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    kinds, R_WO, p_WO, v_WO, dims = obstacles
    ints, floats = model.packed(obstacles, model.pair_arrays)
    compiled = native.Clearances(ints, floats)
    reach, args, pair_arrays = model.reach, model._kernel_args(), model.pair_arrays

    def numba(QAB):
        QA, QB = QAB
        M = QA.shape[0]
        out = (np.empty(M, np.int64), np.empty(M), np.empty(M), np.empty(M), np.empty(M, np.int64))
        for tolerance in (np.inf, 1e-3):
            SK.certify_segments(QA, QB, reach, 0.0, 0.0, 0.0, tolerance, MIN_PIECE, MAX_EVALUATIONS, *args, kinds,
                                R_WO, p_WO, v_WO, dims, *pair_arrays, *out)
        return out

    def compiled_certify(QAB):
        QA, QB = QAB
        compiled.certify_segments(QA, QB, reach, v_WO, 0.0, 0.0, 0.0, np.inf, MIN_PIECE, MAX_EVALUATIONS)
        return compiled.certify_segments(QA, QB, reach, v_WO, 0.0, 0.0, 0.0, 1e-3, MIN_PIECE, MAX_EVALUATIONS)

    identical = True
    for QAB in pairs:
        a, b = numba(QAB), compiled_certify(QAB)
        identical &= bool(np.array_equal(a[0], b[0]) and np.array_equal(a[4], b[4])
                          and all(np.allclose(x, y, rtol=0.0, atol=1e-9, equal_nan=True) for x, y in zip(a[1:4], b[1:4])))
    calls = max(1, 64 // N)
    return interleaved({"numba": numba, "native": compiled_certify}, pairs, calls, rounds), identical


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
    return interleaved({"numba": numba, "native": compiled}, Qs, calls, rounds), identical


def run_case(case: Case) -> dict:
    """One implementation pair at one ``N``: ns per configuration, ratios, identical answers."""
    row = dict(robot=case["robot"], case=case["case"], N=case["N"], cpu=cpu_model(), load_average=load_average())
    from drake_mh.scene.compiled_check import compiled_core

    _native = compiled_core()
    row["built"] = _native is not None
    if not row["built"]:
        return row

    N = case["N"]
    rounds = QUICK_ROUNDS if case.quick else ROUNDS
    if case["case"] in CERTIFY:
        measured = None if N > CERTIFY_MAX else _certify(case["robot"], _native, case["case"] == CERTIFY[1], N, rounds)
        if measured is None:
            row["skipped"] = True  # no archive, or more segments than a round should take
            return row
        times, row["identical"] = measured
        return _ratios(row, times, N)
    robot = _robot(case["robot"])
    rng = np.random.default_rng(0)
    Qs = [np.ascontiguousarray(rng.uniform(robot.lower, robot.upper, (N, robot.nq)))
          for _ in range(ONE_CONFIGURATIONS if N == 1 else BATCHES)]
    if case["case"] in CLEARANCES:
        times, row["identical"] = _clearances(robot, _native, case["case"] == CLEARANCES[1], Qs, rounds)
    elif case["case"] in SCENES:
        times, row["identical"] = _check(robot, _native, case["case"], Qs, rounds)
    else:
        times, row["identical"] = _kinematics(robot, _native, case["case"] == "fk+J", Qs, rounds)
    return _ratios(row, times, N)


def _ratios(row: dict, times: dict, N: int) -> dict:
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
    rows = [r for r in finished(records) if r.get("built") and not r.get("skipped")]
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
