"""Motion benchmark: every registered planner on the MotionBenchMaker-like problem sets.

Methods × problem sets × problems × seeds, the methods interleaved per problem (all methods run
on one problem before the next, so they share the machine's load). Problems come from
:func:`drake_mh.planning.problems.problem_set` — seven sets like MotionBenchMaker's (table pick,
table under pick, bookshelf small / tall / thin, box, cage), start and goal generated and
certified free by us, self-collision checked — for the bundled capsule Panda and for
example-robot-data's Panda with its hand (meshes; when installed). With the environment
variable ``DRAKE_MH_MBM_ARCHIVE`` set to a downloaded ``problems.tar.bz2`` of the
``vamp-planner`` source distribution, the original MotionBenchMaker Panda problems join as sets
``mbm/<set>`` (robot: the Panda with MotionBenchMaker's hand; never downloaded here).

Every method is called through :func:`drake_mh.planning.solve_motion` with the same timeout and
verified the same way (the whole motion certified collision-free, then retimed and certified);
its first call in a process runs once untimed (compilation, program builds). Recorded per
case: verified success, planning time (wall and process CPU; neither goal IK nor verification),
path length in joint space, executed duration after retiming, the minimum certified clearance
along the executed motion, the largest joint jerk and whether the motion keeps the robot's jerk
limits (toppra's do not: its accelerations step; ``solve_motion(retime="ruckig")`` does), the
problem's numbers (obstacles, whether the straight line is certified free), the CPU model and the 1-minute load average. The report ranks
the methods (Friedman, Wilcoxon-Holm against the best, Derrac et al. 2011) on the time to a
verified motion (a failure ranks last) and, in the summary, on path length; it shows a 3-D
animation of one problem per set (full runs only). Published anchors (VAMP, cuRobo) are printed
beside, marked as not measured in this run.

A method that is not registered here (an optional peer such as OMPL without its wheel) is
listed as unavailable, not run. ``DRAKE_MH_MOTION_METHODS=a,b,...`` restricts the methods and
``DRAKE_MH_MOTION_ROBOTS=panda,panda_hand,panda_hand_mbm`` restricts the robots,
``DRAKE_MH_MOTION_PROBLEMS=N`` sets N problems per set and robot (one replicate) for a shorter
full run. ``DRAKE_MH_MOTION_SCENES=cell.sdf,other.yaml`` adds the cell of each scene file
(any format :meth:`drake_mh.scene.Scene.load` reads) as set ``file/<file name>``: start/goal pairs
drawn in joint space and certified free there
(:func:`drake_mh.planning.problems.scene_problem_set`), for every robot, in the full grid and
(problem 0 of the first file) in the quick one. Full run: 7 sets × 8 problems × 2 seeds on the capsule Panda and
7 × 2 × 1 on the Panda with its hand, every registered method (about twenty), 10 s per plan:
a few hours on two loaded cores. ``--quick``: one table problem, a handful of methods, 1 s each.

Run: ``drake-mh study motion_benchmark [--quick]`` or ``python studies/motion_benchmark.py [--quick]``.
"""

from __future__ import annotations

import os

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average
from drake_mh.study.report.summary import (cell, cpu_and_load, finished, group_by, markdown_table, median, p95,
                                           rank_lines, share, values)

TIMEOUT = 10.0
"""[s] per plan (full grid)."""
QUICK_TIMEOUT = 1.0
"""[s] per plan (quick grid)."""
WARM_TIMEOUT = 0.5
"""[s] of the untimed first call of a method in a process (compilation, program builds)."""
SETS = ("table_pick", "table_under_pick", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "cage")
#: robot -> (problems per set, seeds) in the full grid
ROBOTS = {"panda": (8, 2), "panda_hand": (2, 1)}
MBM_PROBLEMS = 10
"""problems per set read from the MotionBenchMaker archive (full grid)."""
MBM_ROBOT = "panda_hand_mbm"
SET_SEED = 2024
"""seed of the generated problem sets (the same problems for every method and planner seed)."""
QUICK_METHODS = ("straight", "rrt_connect", "drake_kto", "ompl_rrtconnect", "mh_pso")
#: optional peers: listed as unavailable when their module did not register them
OPTIONAL = ("ompl_rrtconnect", "ompl_bitstar")
#: methods whose motion is animated (problem 0, first seed of each set): the first registered one
ANIMATED = ("rrt_connect", "ompl_rrtconnect", "mh_pso", "drake_kto")

#: figures from elsewhere, put beside ours (not measured in this run)
ANCHORS = (
    ("VAMP (ICRA 2024, published)", "MotionBenchMaker Panda, 7 x 100", "-", "0.035 median", "SIMD RRT-Connect, C++, "
     "AMD Ryzen 9 7950X; its own sphere model"),
    ("VAMP (built by hand, measured on this kind of machine)", "MotionBenchMaker Panda, 699 / 699", "100",
     "0.058-0.064 median (~0.2 with simplification)", "paths valid under its spheres; 134 / 200 clear under our "
     "capsule Panda (-8.4 mm)"),
    ("cuRobo (published)", "MotionBenchMaker + MpiNets, 2,600", "99.85", "31 median", "GPU"),
)


def _methods() -> list[str]:
    """Every registered method, or those of ``DRAKE_MH_MOTION_METHODS`` (comma-separated) that are."""
    from drake_mh.planning import available_motion_methods

    registered = list(available_motion_methods())
    chosen = [m.strip() for m in os.environ.get("DRAKE_MH_MOTION_METHODS", "").split(",") if m.strip()]
    return [m for m in chosen if m in registered] if chosen else registered


def _unavailable() -> list[str]:
    registered = set(_methods())
    return [m for m in OPTIONAL if m not in registered]


def _mbm_archive() -> str | None:
    path = os.environ.get("DRAKE_MH_MBM_ARCHIVE")
    return path if path and os.path.exists(path) else None


def _chosen_robots() -> set[str]:
    """Robots of ``DRAKE_MH_MOTION_ROBOTS`` (comma-separated; empty: all)."""
    return {r.strip() for r in os.environ.get("DRAKE_MH_MOTION_ROBOTS", "").split(",") if r.strip()}


def _robots() -> dict:
    """:data:`ROBOTS` (robots whose models are installed); ``DRAKE_MH_MOTION_PROBLEMS=N``: N
    problems per set and robot, one replicate."""
    from drake_mh.robot.examples import example_robot_data_root

    robots = {r: v for r, v in ROBOTS.items() if r == "panda" or example_robot_data_root() is not None}
    chosen = _chosen_robots()
    if chosen:
        robots = {r: v for r, v in robots.items() if r in chosen}
    count = os.environ.get("DRAKE_MH_MOTION_PROBLEMS", "").strip()
    if count.isdigit() and int(count) > 0:
        robots = {r: (int(count), 1) for r in robots}
    return robots


def _scene_files() -> dict[str, str]:
    """``{"file/<file name>": path}`` of ``DRAKE_MH_MOTION_SCENES`` (comma-separated scene files)."""
    paths = [p.strip() for p in os.environ.get("DRAKE_MH_MOTION_SCENES", "").split(",") if p.strip()]
    return {f"file/{os.path.basename(p)}": p for p in paths}


def _grid(quick: bool) -> list[dict]:
    methods = _methods()
    if quick:
        chosen = [m for m in QUICK_METHODS if m in methods]
        names = ["table_pick", *list(_scene_files())[:1]]
        return [{"robot": "panda", "set": name, "problem": 0, "rep": 0, "method": m} for name in names for m in chosen]
    cases = []
    for robot, (count, seeds) in _robots().items():
        for name in (*SETS, *_scene_files()):
            for problem in range(count):
                for rep in range(seeds):
                    cases += [{"robot": robot, "set": name, "problem": problem, "rep": rep, "method": m}
                              for m in methods]
    if _mbm_archive() and (not _chosen_robots() or MBM_ROBOT in _chosen_robots()):
        from drake_mh.planning.problems import MBM_SETS

        for name in MBM_SETS:
            for problem in range(MBM_PROBLEMS):
                cases += [{"robot": MBM_ROBOT, "set": f"mbm/{name}", "problem": problem, "rep": 0, "method": m}
                          for m in methods]
    return cases


_CACHE: dict = {"problems": {}, "warm": set(), "mbm": None}


def _problem(robot: str, name: str, index: int):
    """``(MotionProblem, straight_free)`` of one grid problem, generated once per process."""
    key = (robot, name, index)
    if key not in _CACHE["problems"]:
        from drake_mh.planning.problems import motionbenchmaker_set, problem_set, scene_problem_set

        if name.startswith("file/"):
            found = scene_problem_set(_scene_files()[name], robot, count=1, seed=SET_SEED, first=index)
            _CACHE["problems"][key] = (found[0], found.info[0]["straight_free"])
        elif name.startswith("mbm/"):
            if _CACHE["mbm"] is None:
                _CACHE["mbm"] = {}
            sets = _CACHE["mbm"]
            if name not in sets:
                sets[name] = motionbenchmaker_set(_mbm_archive(), name[4:], robot=robot, count=MBM_PROBLEMS)
            found = sets[name]
            if index >= len(found):
                raise LookupError(f"{name}: only {len(found)} of the first {MBM_PROBLEMS} problems are valid for "
                                  f"{robot} ({len(found.skipped)} skipped: start or goal not certified free)")
            _CACHE["problems"][key] = (found[index], found.info[index]["straight_free"])
        else:
            found = problem_set(name, robot, count=1, seed=SET_SEED, first=index)
            _CACHE["problems"][key] = (found[0], found.info[0]["straight_free"])
    return _CACHE["problems"][key]


def _animate(case: Case, problem, result) -> str:
    """Attach a Meshcat animation of the executed motion with its certified clearance
    (:func:`drake_mh.viz.motion_html`); says what happened."""
    try:
        import drake_mh.viz as viz

        case.attach("motion.html", viz.motion_html(problem, result))
        return "attached"
    except ImportError:
        return "drake_mh.viz not installed"
    except Exception as exc:  # an animation must not sink the numbers
        return f"failed: {type(exc).__name__}: {exc}"[:200]


def run(case: Case) -> dict:
    from drake_mh.planning import solve_motion

    timeout = QUICK_TIMEOUT if case.quick else TIMEOUT
    method = case["method"]
    problem, straight_free = _problem(case["robot"], case["set"], case["problem"])
    warm = (case["robot"], method)
    if warm not in _CACHE["warm"]:  # compile / build once per process, untimed
        solve_motion(problem, method, seed=case.seed, timeout=min(timeout, WARM_TIMEOUT), retime=False)
        _CACHE["warm"].add(warm)
    load = load_average()
    result = solve_motion(problem, method, seed=case.seed, timeout=timeout)
    record = result.record()
    success = bool(result.success)
    record.update(
        method=method, time=result.planning_time, cpu=result.cpu_time,
        error=result.planning_time if success else float("nan"),
        path_length_verified=result.path_length if success else float("nan"), nfe=0,
        obstacles=len(problem.scene.obstacles), straight_free=bool(straight_free),
        joint_distance=float(np.linalg.norm(problem.goal_configurations[0] - problem.q_start)),
        load_average=float(np.nanmean([load, load_average()])), cpu_model=cpu_model(), timeout=timeout)
    if "t_found" in result.info:  # rrt_connect: the kernel's time from the first certified path to the shortcut's end
        record["shortcut_cpu"] = float(result.info["t_total"] - result.info["t_found"])
    animated = next((m for m in ANIMATED if m in _methods()), None)
    if (not case.quick and success and method == animated and case["problem"] == 0 and case["rep"] == 0
            and result.trajectory is not None):
        record["animation"] = _animate(case, problem, result)
    return record


# --- summary --------------------------------------------------------------------------------------


def _problem_table(ok: list[dict]) -> list[str]:
    rows = []
    for (robot, name), group in group_by(ok, "robot", "set").items():
        problems = list({r["problem"]: r for r in group}.values())
        rows.append([robot, name, len(problems), f"{np.mean([r['obstacles'] for r in problems]):.1f}",
                     f"{100 * np.mean([not r['straight_free'] for r in problems]):.0f}",
                     f"{median(r['joint_distance'] for r in problems):.2f}"])
    return markdown_table(["robot", "set", "problems", "obstacles (mean)", "straight line blocked [%]",
                           "start-goal distance, median [rad]"], rows)


def _by_method(rows: list[dict], methods: list[str]) -> dict[str, list[dict]]:
    groups = group_by(rows, "method")
    return {m: groups[m] for m in methods if m in groups}


def _method_table(rows: list[dict], methods: list[str]) -> list[str]:
    table = []
    for method, group in _by_method(rows, methods).items():
        wins = [r for r in group if r["success"]]
        wall = values(wins, "time", 1e3)
        jerk = [r["jerk_limited"] for r in wins if r.get("jerk_limited") is not None]  # None: no jerk limits
        table.append([method, f"{100 * len(wins) / len(group):.0f} ({len(wins)}/{len(group)})",
                      f"{cell(median(wall), '.2f')} / {cell(p95(wall), '.2f')}",
                      cell(median(values(wins, "cpu", 1e3)), ".2f"), cell(median(values(wins, "path_length")), ".2f"),
                      cell(median(values(wins, "duration")), ".2f"), cell(median(values(wins, "min_clearance", 1e3)), ".1f"),
                      f"{100 * np.mean(jerk):.0f}" if jerk else "-"])
    return markdown_table(["method", "verified [%]", "plan wall median / p95 [ms]", "plan CPU median [ms]",
                           "path length median [rad]", "duration median [s]", "certified clearance median [mm]",
                           "within jerk limits [%]"], table)


def _split_lines(rows: list[dict], methods: list[str]) -> list[str]:
    """For the planners that report when they found their first certified path (``t_found``):
    the plan's CPU time without the shortcut after it, and the shortcut's, over verified plans."""
    lines = []
    for method, group in _by_method(rows, methods).items():
        wins = [r for r in group if r["success"] and r.get("shortcut_cpu") is not None]
        if wins:
            first = [(r["cpu"] - r["shortcut_cpu"]) * 1e3 for r in wins]
            lines.append(f"- `{method}`: to the first certified path (CPU time minus the shortcut) median "
                         f"{median(first):.2f} ms, p95 {p95(first):.2f} ms; the shortcut median "
                         f"{median(values(wins, 'shortcut_cpu', 1e3)):.2f} ms")
    return ["", "Plan and shortcut, where the planner reports both:", ""] + lines if lines else []


def _set_table(rows: list[dict], methods: list[str]) -> list[str]:
    sets = list(group_by(rows, "set"))
    table = [[method] + [f"{100 * share(g):.0f}" if (g := [r for r in group if r["set"] == name]) else "-"
                         for name in sets] for method, group in _by_method(rows, methods).items()]
    return markdown_table(["method"] + sets, table)


def summarize(records: list[dict]) -> str:
    ok = finished(records)
    if not ok:
        return "no finished case"
    methods = list(group_by(ok, "method"))
    timeouts = ", ".join(f"{t:g}" for t in sorted({r["timeout"] for r in ok}))
    lines = [f"{cpu_and_load(ok, cpu='cpu_model', digits=2)}; {timeouts} s per plan. Success = verified: the whole "
             "motion certified collision-free (self-collision included) and retimed under the robot's limits; times "
             "are planning only (no goal IK, no verification), over the verified plans.", "", "### Problems", ""]
    lines += _problem_table(ok)
    for robot, rows in group_by(ok, "robot").items():
        lines += ["", f"### {robot}: all sets", ""] + _method_table(rows, methods) + _split_lines(rows, methods)
        lines += ["", f"Verified [%] per set ({robot}):", ""] + _set_table(rows, methods)
    if len(methods) > 1:
        blocks = ("robot", "set", "problem", "rep")
        lines += ["", "### Ranks", ""] + rank_lines(ok, methods, "error", blocks, "Time to a verified motion") + [""]
        lines += rank_lines(ok, methods, "path_length_verified", blocks, "Path length of a verified motion")
    lines += ["", "### Anchors (not measured in this run)", ""]
    lines += markdown_table(["planner", "problems", "solved [%]", "plan time [ms]", "note"], ANCHORS)
    missing = _unavailable()
    if missing:
        lines += ["", f"Unavailable here (optional dependency missing, not registered): {', '.join(missing)}."]
    animations = [r for r in ok if r.get("animation")]
    if animations:
        lines += ["", "Animations: " + "; ".join(f"{r['set']} ({r['method']}): {r['animation']}" for r in animations)]
    return "\n".join(lines)


study = Study(
    name="motion_benchmark",
    run=run,
    grid=_grid(quick=False),
    quick_grid=_grid(quick=True),
    seed=0,
    fields=Fields(method="method", success="success", time="time", error="error", nfe="nfe",
                  instance=("robot", "set", "problem", "rep"), group_by=("robot", "set"), error_unit="s",
                  conditions=f"{TIMEOUT:g} s per plan ({QUICK_TIMEOUT:g} s quick); success = the whole motion "
                             "certified collision-free and retimed; error = planning time of a verified motion"),
    description=(
        "Point-to-point motion planning among obstacles: every registered planner (sampling, metaheuristic via-point "
        "optimization, Drake KTO, OMPL when installed) on seven MotionBenchMaker-like problem sets generated and "
        "certified by drake_mh, for the capsule Panda and the Panda with its hand (meshes); every motion verified "
        "the same way (certified collision-free, retimed). Error = planning time of a verified motion (failures "
        "rank last)."),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
