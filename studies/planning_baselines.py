"""Planning baselines on a Panda shelf/table scene: Drake KTO + SNOPT and OMPL beside ``straight``.

One scene built from boxes (a table in front of the arm, a three-board bookshelf beside it, open
towards the arm) and eight start/goal pairs between configurations above the table and inside
the shelf (each found once by collision-free hybrid IK, flange pointing down over the table and
into the shelf, then rounded to 1e-4 rad and written below). Every method plans with the same
:class:`~drake_mh.planning.MotionProblem` (clearance 0) and is verified the same way
(:func:`~drake_mh.planning.verify_motion`: the whole motion certified, then retimed):

* ``straight`` — the baseline;
* ``drake_kto`` — Drake's ``KinematicTrajectoryOptimization`` + SNOPT from the straight line
  (margin: the sphere model's bound); ``drake_kto margin 0`` asks Drake for the problem's
  clearance only; ``drake_kto_warm`` from the ``rrt_connect`` path;
* ``ompl_rrtconnect`` / ``ompl_bitstar`` — OMPL 2.0.1 with our checker (when installed: the
  ``peers`` extra); ``rrt_connect`` — ours, for reference.

Recorded per case: verified success, planning time (wall and CPU, neither verification nor
retiming), path length in joint space, retimed duration, certified clearance; for the KTO
rows also SNOPT's own success flag, and whether it disagrees with the verified outcome; for a
returned motion that is not verified, Drake's exact distance at 10 points per segment (does it
really collide, or is it clear but not certified under the sphere model?).
A method's first case in a process runs once untimed (compilation, the KTO program's build),
then the timed run. 10 s per plan.

Run: ``drake-mh study planning_baselines [--quick]`` or ``python studies/planning_baselines.py``.
"""

from __future__ import annotations

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import cpu_and_load, finished, group_by, markdown_table, median, p95, values

TIMEOUT = 10.0

CONFIGURATIONS = {  # hybrid IK with the scene, clearance 0.03 m, q_ref = home (ref_weight 0.05), rounded
    "table_front": [-0.2687, 0.2081, -0.1978, -2.169, 0.0594, 2.3722, -0.5051],
    "table_near": [0.1487, -0.1102, 0.1723, -2.4224, 0.0256, 2.3137, 0.3027],
    "table_right": [-0.4955, 0.1051, -0.4254, -2.0307, 0.0509, 2.1259, -0.9457],
    "shelf_middle": [0.0972, 0.9756, 1.5217, -1.5073, 0.2653, 3.1593, 0.3317],
    "shelf_bottom": [0.0603, 1.7535, 1.5162, -1.6875, -0.3699, 3.3293, 0.1854],
    "shelf_middle_far": [0.5366, 0.9631, 0.8045, -0.6785, 0.7987, 2.5729, 0.1614],
}

PROBLEMS = ("table_front>shelf_middle", "table_right>shelf_bottom", "shelf_middle>shelf_bottom",
            "table_near>shelf_middle_far", "home>shelf_bottom", "shelf_middle_far>table_right",
            "shelf_bottom>shelf_middle_far", "table_front>table_right")

#: row label -> (registered method, options)
VARIANTS = {
    "straight": ("straight", {}),
    "drake_kto": ("drake_kto", {}),
    "drake_kto margin 0": ("drake_kto", {"margin": 0.0}),
    "drake_kto_warm": ("drake_kto_warm", {}),
    "rrt_connect": ("rrt_connect", {}),
    "ompl_rrtconnect": ("ompl_rrtconnect", {}),
    "ompl_bitstar": ("ompl_bitstar", {}),
}


def _available() -> list[str]:
    from drake_mh.planning import available_motion_methods

    registered = available_motion_methods()
    return [label for label, (method, _) in VARIANTS.items() if method in registered]


def _unavailable() -> list[str]:
    available = set(_available())
    return [label for label in VARIANTS if label not in available]


def shelf_scene(robot):
    """A table in front of the arm and a bookshelf beside it (boxes only)."""
    from drake_mh.scene import Box, Scene

    scene = Scene(robot)
    scene.add("table", Box((0.6, 1.0, 0.04)), [0.6, -0.1, 0.08])
    scene.add("shelf_back", Box((0.6, 0.02, 1.0)), [0.4, 0.8, 0.5])
    scene.add("shelf_side_a", Box((0.02, 0.35, 1.0)), [0.1, 0.625, 0.5])
    scene.add("shelf_side_b", Box((0.02, 0.35, 1.0)), [0.7, 0.625, 0.5])
    for i, z in enumerate((0.1, 0.42, 0.74, 1.0)):
        scene.add(f"shelf_board{i}", Box((0.6, 0.35, 0.02)), [0.4, 0.625, z])
    return scene


_WORLD: dict = {}


def _world():
    """The robot and the scene, once per process (the KTO program is cached per scene)."""
    if not _WORLD:
        import drake_mh

        robot = drake_mh.load_robot("panda")
        _WORLD.update(robot=robot, scene=shelf_scene(robot), warm=set())
    return _WORLD["robot"], _WORLD["scene"]


def problem(name: str):
    from drake_mh.planning import MotionProblem

    robot, scene = _world()
    start, goal = name.split(">")
    q = {**{k: np.array(v) for k, v in CONFIGURATIONS.items()}, "home": robot.home}
    return MotionProblem(robot, scene, q[start], q[goal], name=name)


def run(case: Case) -> dict:
    from drake_mh.planning import solve_motion

    method, options = VARIANTS[case["method"]]
    motion = problem(case["problem"])
    if case["method"] not in _WORLD["warm"]:  # compile / build once, untimed
        solve_motion(motion, method, seed=case["seed"], timeout=TIMEOUT, retime=False, **options)
        _WORLD["warm"].add(case["method"])
    load = load_average()
    result = solve_motion(motion, method, seed=case["seed"], timeout=TIMEOUT, **options)
    record = result.record()
    record.update(method=case["method"], time=result.planning_time, cpu=result.cpu_time,
                  error=result.path_length if result.success else float("nan"), nfe=0, load_average=load,
                  cpu_model=cpu_model())
    if result.path is not None and not result.success:  # does the unverified motion really collide?
        s = np.linspace(0.0, 1.0, 11)[:-1, None]
        P = result.path
        dense = np.concatenate([a + s * (b - a) for a, b in zip(P[:-1], P[1:])] + [P[-1:]])
        record["exact_min_sampled"] = float(np.min(motion.scene.exact_min_distance(dense)))
    flag = result.info.get("solver_success")
    if flag is not None:
        record["solver"] = result.info.get("solver", "")
        record["solver_success"] = bool(flag)
        record["solver_status"] = result.info.get("solver_status", "")
        record["snopt_info"] = result.info.get("snopt_info")
        record["disagrees"] = bool(flag) != bool(result.success)
    return record


def _row(label: str, rows: list[dict]) -> list:
    wins = [r for r in rows if r["success"]]
    flags = [r for r in rows if "disagrees" in r]
    disagree = "—"
    if flags:
        false_ok = sum(1 for r in flags if r["solver_success"] and not r["success"])
        false_fail = sum(1 for r in flags if not r["solver_success"] and r["success"])
        disagree = f"{false_ok} / {false_fail} ({false_ok + false_fail} of {len(flags)})"
    lost = [r for r in rows if not r["success"]]
    collide = sum(1 for r in lost if r.get("exact_min_sampled", np.inf) < 0)
    graze = sum(1 for r in lost if r.get("exact_min_sampled", -np.inf) >= 0)
    why = f"{collide} / {graze} / {len(lost) - collide - graze}" if lost else "—"
    wall = values(rows, "time", 1e3)
    return [label, f"{len(wins)}/{len(rows)}", f"{median(wall):.1f}", f"{median(values(rows, 'cpu', 1e3)):.1f}",
            f"{p95(wall):.1f}", f"{median(values(wins, 'path_length')):.2f}", f"{median(values(wins, 'duration')):.2f}",
            disagree, why]


def summarize(records: list[dict]) -> str:
    ok = finished(records)
    if not ok:
        return "no finished case"
    groups = group_by(ok, "method")
    lines = [f"{cpu_and_load(ok, cpu='cpu_model')}; {TIMEOUT:.0f} s per plan; {len(group_by(ok, 'problem'))} problems",
             ""] + markdown_table(
        ["method", "verified", "median plan wall [ms]", "median plan CPU [ms]", "p95 wall [ms]",
         "median path length [rad] (verified)", "median duration [s]",
         "solver flag: ok but not verified / failed but verified",
         "not verified: collides (exact, sampled) / clear but not certified / no path"],
        [_row(label, groups[label]) for label in VARIANTS if label in groups])
    missing = _unavailable()
    if missing:
        lines += ["", f"Not available here (not registered): {', '.join(missing)}."]
    failed = [r for r in ok if not r["success"] and r["method"] != "straight"]
    if failed:
        lines += ["", "Failures (method, problem, seed: message):", ""]
        lines += [f"* {r['method']}, {r['problem']}, {r['seed']}: {r['message'][:140]}" for r in failed]
    return "\n".join(lines)


study = Study(
    name="planning_baselines",
    run=run,
    grid={"problem": list(PROBLEMS), "method": _available(), "seed": [0, 1, 2]},
    quick_grid={"problem": [PROBLEMS[0]], "method": [m for m in _available() if m in ("straight", "drake_kto",
                                                                                       "ompl_rrtconnect")],
                "seed": [0]},
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe",
                  instance=("problem", "seed"), error_unit="rad", rank=False,
                  conditions=f"{TIMEOUT:.0f} s per plan; success = the whole motion certified collision-free "
                             "(sphere model, clearance 0) and retimed"),
    description=("Drake KinematicTrajectoryOptimization + SNOPT and OMPL (RRT-Connect, BIT*) beside the straight line "
                 "and rrt_connect on a Panda table/bookshelf scene, every answer verified by drake_mh (certified "
                 "motion), the solver's own success flag compared with the verified outcome."),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
