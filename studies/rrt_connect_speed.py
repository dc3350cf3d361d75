"""rrt_connect on Panda table / shelf / slot problems: time (wall and CPU), success, cost split.

Per scene (the bundled Panda, obstacles from boxes and cylinders, MotionBenchMaker's ready
configuration as the start, goal configurations with the flange inside the fixture, drawn by
batched sampling and checked free), ``rrt_connect`` and ``rrt_connect_smooth`` run
interleaved on every problem and seed, after :func:`drake_mh.planning.rrt_connect.prepare`
(no compilation in any clock). Reported per method:

* success (verified by :func:`drake_mh.planning.verify_motion`: the whole path certified);
* planning time, median and 95th percentile, wall and CPU (``solve_motion``'s clocks: the
  planner certifies every edge itself, so this is "plan + certification");
* the verification's time (``verify_motion`` without retiming: an independent certificate with
  a 1 mm tolerance on the reported clearance), and plan + verification;
* tree nodes, motion checks, configurations checked, path length [rad];
* the cost split inside the kernel from a profiled pass (``profile=True``): sampling, nearest
  neighbours, batched checks, certification of motions within their margin, shortcutting
  (its own checks included).

With ``self`` scenes the robot's link pairs are checked too (``Scene(self_collision=True)``).

With the environment variable ``DRAKE_MH_MBM_ARCHIVE`` set to a downloaded ``problems.tar.bz2``
of the ``vamp-planner`` source distribution, the original MotionBenchMaker Panda problems join
as scenes ``mbm/<set>`` (of the first :data:`MBM_PROBLEMS` problems of each set, those certified
free for the Panda with MotionBenchMaker's hand, 778 spheres, self-collision checked; never
downloaded here), and a third method runs interleaved on them: ``rrt_connect (no pair
tables)``, the same planner on a copy of each scene whose self-collision pairs have no floor
tables (:mod:`drake_mh.scene.pair_table`): the code before those tables, as the same-run
baseline (same trees: the tables change the cost of each check, not its answer).
Where the compiled core is built (``drake_mh._native``), ``rrt_connect`` plans through its C++
planner, and a further method runs interleaved on every problem: ``rrt_connect (numba)``, the
same planner through the numba kernel (a copy of each problem's scene bound with
``DRAKE_MH_COMPILED_CORE=0``; same seed, same path), the same-run baseline of the port.
The batched checks are the scene's :func:`drake_mh.scene.kernels.states.check_states` (early
exit, two clearances per link and link pair); the MotionBenchMaker-like figures of
:mod:`drake_mh.planning.rrt_connect` (its 0.5 ms median target) come from the problem sets of
:mod:`drake_mh.planning.problems`, not from this study's scenes.
The 1-minute load average and the CPU are recorded (shared machines: compare within a run).

Run: ``drake-mh study rrt_connect_speed [--quick]`` or ``python studies/rrt_connect_speed.py [--quick]``.
"""

from __future__ import annotations


import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cpu_and_load, finished, markdown_table

SCENES = ("table", "shelf", "slot", "table self")
METHODS = ("rrt_connect", "rrt_connect_smooth")
BASELINE = "rrt_connect (no pair tables)"
NUMBA = "rrt_connect (numba)"
MBM_PROBLEMS = 5
READY = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)  # MotionBenchMaker's start
PROBLEMS, SEEDS = 20, 3
SPLIT = ("t_sample", "t_nn", "t_check", "t_certify", "t_shortcut")


def _scene(robot, name: str):
    """The fixture and the box its goals' flange positions are drawn in."""
    from drake_mh.scene import Box, Cylinder, Scene, Sphere

    scene = Scene(robot, self_collision=name.endswith("self"))
    kind = name.split()[0]
    if kind == "table":  # a table with two cans, a block and a ball; reach between them
        scene.add("table", Box((0.8, 1.4, 0.05)), [0.6, 0.0, 0.1])
        scene.add("can1", Cylinder(0.04, 0.2), [0.5, 0.2, 0.225])
        scene.add("can2", Cylinder(0.04, 0.2), [0.6, -0.15, 0.225])
        scene.add("block", Box((0.1, 0.1, 0.15)), [0.45, -0.35, 0.2])
        scene.add("ball", Sphere(0.05), [0.7, 0.05, 0.175])
        return scene, ([0.35, -0.45, 0.15], [0.8, 0.45, 0.35])
    if kind == "shelf":  # three compartments 30 cm high, 40 cm deep; reach into the middle one
        x0 = 0.65
        scene.add("back", Box((0.02, 0.8, 1.2)), [x0 + 0.2, 0.0, 0.6])
        scene.add("left", Box((0.4, 0.02, 1.2)), [x0, 0.4, 0.6])
        scene.add("right", Box((0.4, 0.02, 1.2)), [x0, -0.4, 0.6])
        for i, z in enumerate((0.2, 0.5, 0.8, 1.2)):
            scene.add(f"board{i}", Box((0.4, 0.8, 0.02)), [x0, 0.0, z])
        return scene, ([0.5, -0.3, 0.55], [0.75, 0.3, 0.75])
    # slot: two boards 22 cm apart and a back wall, the hand inside (a narrow passage)
    scene.add("floor", Box((0.5, 0.9, 0.02)), [0.65, 0.0, 0.4])
    scene.add("roof", Box((0.5, 0.9, 0.02)), [0.65, 0.0, 0.64])
    scene.add("back", Box((0.02, 0.9, 0.6)), [0.91, 0.0, 0.5])
    return scene, ([0.6, -0.2, 0.41], [0.8, 0.2, 0.63])


def _problems(robot, name: str, count: int, rng) -> list:
    from drake_mh.planning import MotionProblem

    scene, (lo, hi) = _scene(robot, name)
    found = []
    while len(found) < count:
        Q = robot.random_configurations(100_000, rng=rng)
        p = robot.batch.fk(Q)[:, :3, 3]
        Q = Q[np.all((p >= lo) & (p <= hi), axis=1)]
        found.extend(Q[scene.collision_free(Q)])
    return [MotionProblem(robot, scene, np.array(READY), q, name=f"{name}/{i}") for i, q in enumerate(found[:count])]


def _mbm_sets() -> list:
    """``["mbm/<set>", ...]`` when ``DRAKE_MH_MBM_ARCHIVE`` names a readable file, else ``[]``."""
    import os

    from drake_mh.planning.problems import MBM_SETS

    archive = os.environ.get("DRAKE_MH_MBM_ARCHIVE", "")
    return [f"mbm/{name}" for name in MBM_SETS] if archive and os.path.isfile(archive) else []


def _mbm_problems(scene: str, count: int, tables: bool = True) -> list:
    """The first ``count`` problems of MotionBenchMaker set ``mbm/<set>`` that are certified free
    for the Panda with its hand; with ``tables=False``, on a fresh copy of the scene whose
    self-collision pairs have no floor tables (``CollisionModel(pair_tables=False)``: the
    baseline)."""
    import os

    from drake_mh.planning.problems import motionbenchmaker_set
    from drake_mh.scene.batch import CollisionModel

    problems = list(motionbenchmaker_set(os.environ["DRAKE_MH_MBM_ARCHIVE"], scene.split("/")[1], count=count))
    if not tables:
        for problem in problems:
            s = problem.scene
            s.__dict__["collision_model"] = CollisionModel(s.robot, s.sphere_model, s.collision_model.self_pairs,
                                                           pair_tables=False)
    return problems


def _numba_bound(problems: list, fresh) -> dict:
    """``{name: problem}``: each problem on a copy of its scene (``fresh(problem)``) whose planner
    binding was made with ``DRAKE_MH_COMPILED_CORE=0``, so that ``rrt_connect`` plans there through
    the numba kernel (:func:`drake_mh.planning.rrt_connect.prepare` compiles or loads it)."""
    import os

    from drake_mh.planning.rrt_connect import prepare
    from drake_mh.scene.compiled_check import ENVIRONMENT

    before = os.environ.get(ENVIRONMENT)
    os.environ[ENVIRONMENT] = "0"
    try:
        copies = {p.name: fresh(p) for p in problems}
        for copy in copies.values():
            prepare(copy)
    finally:
        if before is None:
            del os.environ[ENVIRONMENT]
        else:
            os.environ[ENVIRONMENT] = before
    return copies


def run(case: Case) -> dict:
    import drake_mh
    from drake_mh.planning import MotionProblem, solve_motion
    from drake_mh.planning.rrt_connect import prepare
    from drake_mh.scene.compiled_check import compiled_core

    mbm = case["scene"].startswith("mbm/")
    native = compiled_core() is not None
    if mbm:
        count = 2 if case.quick else MBM_PROBLEMS
        problems = _mbm_problems(case["scene"], count)
        baseline = dict(zip((p.name for p in problems), _mbm_problems(case["scene"], count, tables=False)))
        copies = iter(_mbm_problems(case["scene"], count)) if native else None
        kernel = _numba_bound(problems, lambda p: next(copies)) if native else {}
    else:
        robot = drake_mh.load_robot("panda")
        problems = _problems(robot, case["scene"], 4 if case.quick else PROBLEMS, case.instance_rng)
        baseline = {}
        kernel = _numba_bound(problems, lambda p: MotionProblem(robot, _scene(robot, case["scene"])[0], p.q_start,
                                                                p.goal, name=p.name)) if native else {}
    methods = METHODS + ((BASELINE,) if mbm else ()) + ((NUMBA,) if native else ())
    seeds = 1 if case.quick else SEEDS
    prepared = prepare(problems[0])

    def solve(problem, method, seed, **options):
        if method == BASELINE:
            return solve_motion(baseline[problem.name], "rrt_connect", seed=seed, timeout=10.0, retime=False,
                                **options)
        if method == NUMBA:
            return solve_motion(kernel[problem.name], "rrt_connect", seed=seed, timeout=10.0, retime=False, **options)
        return solve_motion(problem, method, seed=seed, timeout=10.0, retime=False, **options)

    rows = {m: [] for m in methods}
    straight = [solve_motion(p, "straight", retime=False).success for p in problems]
    loads = [load_average()]
    for problem in problems:
        for seed in range(seeds):
            for method in methods:  # interleaved
                r = solve(problem, method, seed)
                rows[method].append((r.success, r.planning_time, r.cpu_time, r.verify_time, r.info.get("nodes", 0),
                                     r.info.get("motions", 0), r.info.get("states", 0), r.path_length))
        loads.append(load_average())
    split = {m: dict.fromkeys(SPLIT + ("t_total",), 0.0) for m in methods}
    for problem in problems:  # a profiled pass: where the time goes
        for method in methods:
            r = solve(problem, method, 0, profile=True)
            for key in split[method]:
                split[method][key] += r.info.get(key, 0.0)
    out = {"success": True, "problems": len(problems), "seeds": seeds, "straight_free": float(np.mean(straight)),
           "prepare [s]": prepared, "cpu": cpu_model(), "load_average": float(np.mean(loads)),
           "load_max": float(np.max(loads))}
    for method, values in rows.items():
        A = np.array(values, dtype=float)
        ok = A[:, 0] > 0
        tag = method
        out[f"{tag} success"] = float(np.mean(ok))
        for col, name in ((1, "wall"), (2, "cpu"), (3, "verify")):
            out[f"{tag} {name} median [s]"] = float(np.median(A[:, col])) if col < 3 or ok.any() else float("nan")
            out[f"{tag} {name} p95 [s]"] = float(np.percentile(A[:, col], 95)) if col < 3 or ok.any() else float("nan")
        out[f"{tag} plan+verify median [s]"] = float(np.median(A[ok, 1] + A[ok, 3])) if ok.any() else float("nan")
        for col, name in ((4, "nodes"), (5, "motions"), (6, "states")):
            out[f"{tag} {name}"] = float(np.median(A[:, col]))
        out[f"{tag} length [rad]"] = float(np.median(A[ok, 7])) if ok.any() else float("nan")
        total = split[method]["t_total"] or 1.0
        for key in SPLIT:
            out[f"{tag} {key} share"] = split[method][key] / total
    out["time"] = out["rrt_connect wall median [s]"]
    out["error"] = float(len(rows["rrt_connect"]) * (1.0 - out["rrt_connect success"]))
    out["states"] = out["rrt_connect states"]
    return out


def summarize(records: list[dict]) -> str:
    order = {name: i for i, name in enumerate(SCENES)}
    ok = sorted(finished(records), key=lambda r: order.get(r["scene"], 99))
    if not ok:
        return "no finished case"
    rows = []
    for r in ok:
        for m in METHODS + tuple(m for m in (BASELINE, NUMBA) if f"{m} success" in r):
            ms = {k: r[f"{m} {k} [s]"] * 1e3 for k in ("wall median", "cpu median", "wall p95", "cpu p95",
                                                       "verify median", "plan+verify median")}
            rows.append([r["scene"], m, f"{r['problems']} × {r['seeds']}", f"{r['straight_free']:.0%}",
                         f"{r[f'{m} success']:.0%}", f"{ms['wall median']:.2f} ({ms['cpu median']:.2f})",
                         f"{ms['wall p95']:.2f} ({ms['cpu p95']:.2f})", f"{ms['verify median']:.2f}",
                         f"{ms['plan+verify median']:.2f}", f"{r[f'{m} nodes']:.0f}", f"{r[f'{m} motions']:.0f}",
                         f"{r[f'{m} states']:.0f}", f"{r[f'{m} length [rad]']:.2f}"])
    lines = [f"{cpu_and_load(ok, loads=('load_average', 'load_max'))} (2 shared cores: wall time includes waiting for a "
             "core, CPU time does not)", ""] + markdown_table(
        ["scene", "method", "problems × seeds", "straight free", "success", "plan median [ms] wall (CPU)",
         "p95 wall (CPU)", "verify median [ms]", "plan + verify median [ms]", "nodes", "motions",
         "configurations checked", "length [rad]"], rows)
    mbm = [r for r in ok if f"{BASELINE} success" in r]
    if mbm:
        lines += ["", "MotionBenchMaker scenes, rrt_connect against the same planner without pair floor tables "
                  "(same run, interleaved): CPU median ratio " + ", ".join(
                      f"{r['scene']} {r[f'{BASELINE} cpu median [s]'] / r['rrt_connect cpu median [s]']:.1f}x"
                      for r in mbm)]
    ported = [r for r in ok if f"{NUMBA} success" in r]
    if ported:
        lines += ["", "rrt_connect through the compiled core (C++) against the numba kernel (same run, interleaved, "
                  "same seeds and paths): median ratio C++ / numba, wall (CPU): " + ", ".join(
                      f"{r['scene']} {r['rrt_connect wall median [s]'] / r[f'{NUMBA} wall median [s]']:.2f} "
                      f"({r['rrt_connect cpu median [s]'] / r[f'{NUMBA} cpu median [s]']:.2f})" for r in ported)]
    lines += ["", "Where rrt_connect's time goes (profiled pass, share of the kernel's time; shortcutting includes "
              "its own checks):", ""] + markdown_table(
        ["scene", "sampling", "nearest neighbours", "batched checks", "certification within margins", "shortcutting"],
        [[r["scene"]] + [f"{r[f'rrt_connect {k} share']:.1%}" for k in SPLIT] for r in ok])
    return "\n".join(lines)


study = Study(
    name="rrt_connect_speed",
    run=run,
    grid={"scene": list(SCENES) + _mbm_sets()},
    quick_grid={"scene": ["table"]},
    fields=Fields(method="scene", success="success", time="time", error="error", nfe="states", rank=False,
                  error_unit="failed runs"),
    description=(
        "rrt_connect and rrt_connect_smooth on Panda table / shelf / slot problems: verified success, planning "
        "time (wall and CPU, median and p95), verification time, tree and check counts, path length, and the "
        "cost split inside the kernel. 'time' is rrt_connect's median planning wall time, 'error' its failed "
        "runs, 'nfe' its median configurations checked."
    ),
    summarize=summarize,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
