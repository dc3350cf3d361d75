"""Obstacle forms: the same cells as primitives, as meshes and as point clouds.

Four parts, each a row of the grid (``part``):

* ``decompose``: CoACD and the cover-excess bound of :mod:`drake_mh.geometry.convex_pieces` on
  the test meshes (``tests/data/``) from an empty cache (cold), then a cache hit (median of 5).
* ``cloud_build``: the point-cloud structure of the batched checks for 50,000 points drawn
  uniformly in [-0.8, 0.8]² x [0, 1] m — the whole shape table (``obstacle_arrays``: grid of
  distance bounds + bounding-box tree; median of 7), the cloud's entry alone by the compiled
  core (where it is built: the table's own) and by the numba kernel (median of 11 rounds, the
  two interleaved), and, beside them, scipy's ``cKDTree`` and a 2 cm Euclidean distance
  transform (median of 7).
* ``batched``: ``Scene.collision_free`` (N = 1024 random configurations of the capsule Panda,
  ns per configuration, median over interleaved rounds; warm = 20 consecutive calls) on the
  shared benchmark scenes (:mod:`drake_mh.scene.benchmark`): ten mixed primitives, the same as
  meshes, the same as a 50,000-point cloud.
* ``plan``: MotionBenchMaker's Panda problems (with ``DRAKE_MH_MBM_ARCHIVE`` set to a
  downloaded ``vamp-planner`` sdist; the Panda with MotionBenchMaker's hand; never downloaded
  here) and our generated sets (:func:`drake_mh.planning.problems.problem_set`, capsule Panda),
  each problem's obstacles given three ways (:func:`drake_mh.scene.benchmark.scene_form`, the
  ``form`` axis): as the primitives; as triangle meshes of them (32-sided cylinders, icospheres)
  loaded as :class:`drake_mh.scene.Mesh`; as one :class:`drake_mh.scene.PointCloud` sampled
  uniformly on their surfaces at :data:`~drake_mh.scene.benchmark.CLOUD_DENSITY` points per m²
  (1 per cm²; VAMP samples a fixed 10,000 per obstacle, then thins to 2 cm), balls of 2.5 mm
  (VAMP's point radius), cropped to the robot's reach. Recorded per case: the scene build
  (meshes: decomposition from an empty cache and from a warm one; every form: the kernels'
  arrays, for a cloud its grid and tree), the batched check on 1024 random configurations
  (the same for every form of a problem), and ``solve_motion(problem, "rrt_connect")`` with its
  defaults (plan + verification + toppra retiming), timed whole (wall and CPU) after one untimed
  call per robot and form in the process. Success is ``solve_motion``'s verified success; a
  problem whose start or goal is not certified free under a form counts as a failure there
  ("not posed").

Full run: 7 MotionBenchMaker sets x 5 problems and 7 generated sets x 3 problems, three forms,
10 s per plan (``DRAKE_MH_FORMS_PROBLEMS=N``: N problems per set of both;
``DRAKE_MH_FORMS_PARTS=batched,cloud_build``: only those parts). ``--quick``: the
bracket and the cube, the cloud build, the batched check at N = 256, and problem 0 of
``table_pick`` (and of ``mbm/table_pick`` when the archive is set), 1 s per plan: a few minutes
once the kernels are compiled.

Run: ``DRAKE_MH_MBM_ARCHIVE=... drake-mh study obstacle_forms [--quick] --workers 1``.
"""

from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path

import numpy as np

from drake_mh.study import Case, Fields, Study
from drake_mh.study.machine import cpu_model, load_average, timed
from drake_mh.study.report.summary import cpu_and_load, finished, group_by, markdown_table, median, p95

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
FORMS = ("primitives", "meshes", "point cloud")
MESHES = ("bin.obj", "bracket.obj", "cube.stl")
QUICK_MESHES = ("bracket.obj", "cube.stl")
SETS = ("table_pick", "table_under_pick", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "box", "cage")
MBM_PROBLEMS, SET_PROBLEMS = 5, 3
MBM_ROBOT, SET_ROBOT = "panda_hand_mbm", "panda"
SET_SEED = 2024
TIMEOUT, QUICK_TIMEOUT = 10.0, 1.0
N_QUERY, QUICK_N_QUERY = 1024, 256
CLOUD_POINTS = 50_000

#: figures from elsewhere (not measured here)
ANCHORS = (
    ("VAMP, CAPT (ICRA 2024, published; Ryzen 9 7950X)", "MotionBenchMaker Panda, point clouds",
     "2.1 ms build, 2.3 ms filtering per problem", "< 10 ns per sphere query", "111 µs planning median"),
)


def _mbm_archive() -> str | None:
    path = os.environ.get("DRAKE_MH_MBM_ARCHIVE")
    return path if path and os.path.exists(path) else None


def _row(part: str, item: str = "-", set_name: str = "-", problem: int = 0, form: str = "-") -> dict:
    return {"part": part, "item": item, "set": set_name, "problem": problem, "form": form}


def _counts() -> tuple[int, int]:
    """``(MotionBenchMaker problems per set, generated problems per set)``; ``DRAKE_MH_FORMS_PROBLEMS=N``
    sets both to N."""
    count = os.environ.get("DRAKE_MH_FORMS_PROBLEMS", "").strip()
    return (int(count), int(count)) if count.isdigit() and int(count) > 0 else (MBM_PROBLEMS, SET_PROBLEMS)


def _grid(quick: bool) -> list[dict]:
    mbm_count, set_count = _counts()
    rows = [_row("decompose", mesh, form="meshes") for mesh in (QUICK_MESHES if quick else MESHES)]
    rows += [_row("cloud_build", f"{CLOUD_POINTS} points", form="point cloud"), _row("batched", "10 mixed")]
    problems = [(name, i) for name in (SETS[:1] if quick else SETS) for i in range(1 if quick else set_count)]
    if _mbm_archive():
        from drake_mh.planning.problems import MBM_SETS

        problems = [(f"mbm/{name}", i) for name in (MBM_SETS[:1] if quick else MBM_SETS)
                    for i in range(1 if quick else mbm_count)] + problems
    rows += [_row("plan", "rrt_connect", name, i, form) for name, i in problems for form in FORMS]
    parts = {p.strip() for p in os.environ.get("DRAKE_MH_FORMS_PARTS", "").split(",") if p.strip()}
    return [r for r in rows if r["part"] in parts] if parts else rows


# --- parts ----------------------------------------------------------------------------------------


def _decompose(case: Case) -> dict:
    from drake_mh._support.cache import temporary_cache
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.scene import Mesh

    with temporary_cache():
        mesh = Mesh(DATA / case["item"])
        convex_pieces.cache_clear()
        wall, cpu = timed(lambda: convex_pieces(mesh))
        pieces = convex_pieces(mesh)
        hit, _ = timed(lambda: (convex_pieces.cache_clear(), convex_pieces(mesh)), 5)
    return {"success": True, "faces": len(mesh.faces), "pieces": len(pieces), "excess": float(pieces.excess),
            "build_cold": wall, "build_cold_cpu": cpu, "build_warm": hit}


def _cloud_build(case: Case) -> dict:
    from scipy import ndimage
    from scipy.spatial import cKDTree

    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.scene.batch import obstacle_arrays
    from drake_mh.scene.cloud_grid import CELL_MIN, GRID_CELLS
    from drake_mh.scene.compiled_check import compiled_core
    from drake_mh.scene.kernels.cloud_table import cloud_table
    from drake_mh.scene.obstacle import Obstacle

    points = case.rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0], (CLOUD_POINTS, 3))
    obstacle = Obstacle("cloud", PointCloud(points, 0.0), np.eye(4))
    cloud_table(points[:100], 0.0, CELL_MIN, float(GRID_CELLS))  # compiled before the clock

    def edt():
        lo = points.min(axis=0)
        cells = np.floor((points - lo) / 0.02).astype(np.int64)
        grid = np.ones(cells.max(axis=0) + 1, bool)
        grid[tuple(cells.T)] = False
        ndimage.distance_transform_edt(grid)

    out = {"success": True, "points": CLOUD_POINTS, "load": load_average()}
    builds = {"table_numba": lambda: cloud_table(points, 0.0, CELL_MIN, float(GRID_CELLS))}
    core = compiled_core()
    if core is not None:  # the table's own build, interleaved round by round with numba's
        core.cloud_table(points[:100], 0.0, CELL_MIN, float(GRID_CELLS))
        builds["table_compiled"] = lambda: core.cloud_table(points, 0.0, CELL_MIN, float(GRID_CELLS))
    rounds = {key: [] for key in builds}
    for _ in range(11):
        for key, build in builds.items():
            rounds[key].append(timed(build))
    for key, pairs in rounds.items():
        out[f"{key}_wall"], out[f"{key}_cpu"] = (float(np.median(v)) for v in zip(*pairs))
    for key, function in (("table", lambda: obstacle_arrays((obstacle,))),
                          ("ckdtree", lambda: cKDTree(points)), ("edt", edt)):
        out[f"{key}_wall"], out[f"{key}_cpu"] = timed(function, 7)
    out["build_structure"] = out["table_wall"]
    out["load_end"] = load_average()
    return out


def _batched(case: Case) -> dict:
    import drake_mh
    from drake_mh.scene.benchmark import BENCHMARK_SCENES, benchmark_scene

    robot = drake_mh.load_robot("panda")
    scenes = dict(zip(FORMS, (benchmark_scene(robot, kind) for kind in BENCHMARK_SCENES[1:])))
    Q = robot.random_configurations(QUICK_N_QUERY if case.quick else N_QUERY, rng=case.rng)
    for scene in scenes.values():
        scene.collision_free(Q)  # compile / bind first
    one = {form: [] for form in FORMS}
    warm = {form: [] for form in FORMS}
    for _ in range(3 if case.quick else 9):
        for form, scene in scenes.items():
            one[form].append(timed(lambda: scene.collision_free(Q))[0])
            warm[form].append(timed(lambda: [scene.collision_free(Q) for _ in range(20)])[0] / 20)
    out = {"success": True, "n_query": len(Q)}
    for form, scene in scenes.items():
        key = form.replace(" ", "_")
        out[f"query_{key}"] = float(np.median(one[form])) / len(Q)
        out[f"query_warm_{key}"] = float(np.median(warm[form])) / len(Q)
        out[f"colliding_{key}"] = float(1.0 - scene.collision_free(Q).mean())
    return out


_CACHE: dict = {"problems": {}, "mbm": {}, "warm": set()}


def _problem(name: str, index: int):
    """The base problem (obstacles as primitives), read or generated once per process."""
    key = (name, index)
    if key not in _CACHE["problems"]:
        from drake_mh.planning.problems import motionbenchmaker_set, problem_set

        if name.startswith("mbm/"):
            if name not in _CACHE["mbm"]:
                _CACHE["mbm"][name] = motionbenchmaker_set(_mbm_archive(), name[4:], robot=MBM_ROBOT,
                                                           count=_counts()[0])
            found = _CACHE["mbm"][name]
            if index >= len(found):
                raise LookupError(f"{name}: only {len(found)} of the first {_counts()[0]} problems are valid for "
                                  f"{MBM_ROBOT} ({len(found.skipped)} skipped: start or goal not certified free)")
            _CACHE["problems"][key] = found[index]
        else:
            _CACHE["problems"][key] = problem_set(name, SET_ROBOT, count=1, seed=SET_SEED, first=index)[0]
    return _CACHE["problems"][key]


def _form_scene(problem, form: str) -> tuple:
    """``(scene, record)``: the problem's scene in ``form`` and its build times."""
    from drake_mh._support.cache import temporary_cache
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.scene.batch import obstacle_arrays
    from drake_mh.scene.benchmark import scene_form

    out = {}
    margin = max(problem.clearance, 0.0)
    if form == "meshes":
        with temporary_cache():
            convex_pieces.cache_clear()
            out["build_cold"], out["build_cold_cpu"] = timed(lambda: scene_form(problem.scene, form, margin=margin))
        convex_pieces.cache_clear()
        scene_form(problem.scene, form)  # fills the disk cache
        convex_pieces.cache_clear()
    found = {}
    out["build_warm"], out["build_warm_cpu"] = timed(lambda: found.setdefault("scene", scene_form(
        problem.scene, form, margin=margin)))
    scene = found["scene"]
    obstacles = tuple(scene.obstacles.values())
    out["build_structure"], out["build_structure_cpu"] = timed(lambda: obstacle_arrays(obstacles), 3)
    if form == "point cloud":
        out["points"] = sum(len(o.shape.points) for o in obstacles)
    return scene, out


def _plan(case: Case) -> dict:
    from drake_mh.errors import DrakeMhError
    from drake_mh.planning import solve_motion

    timeout = QUICK_TIMEOUT if case.quick else TIMEOUT
    base = _problem(case["set"], case["problem"])
    scene, record = _form_scene(base, case["form"])
    record.update(obstacles=len(base.scene.obstacles), timeout=timeout,
                  robot=MBM_ROBOT if case["set"].startswith("mbm/") else SET_ROBOT)
    Q = base.robot.random_configurations(QUICK_N_QUERY if case.quick else N_QUERY,
                                         rng=np.random.default_rng(case.instance_seed))
    scene.collision_free(Q)
    wall = [timed(lambda: scene.collision_free(Q))[0] for _ in range(7)]
    record.update(query=float(np.median(wall)) / len(Q), colliding=float(1.0 - scene.collision_free(Q).mean()))
    try:
        problem = dataclasses.replace(base, scene=scene)
    except DrakeMhError as exc:  # the start or a goal is not certified free in this form
        return record | {"success": False, "posed": False, "message": str(exc)[:200]}
    warm = (base.robot.name, case["form"])
    if warm not in _CACHE["warm"]:  # compile / bind once per process and form, untimed
        solve_motion(problem, "rrt_connect", seed=0, timeout=min(timeout, 0.5))
        _CACHE["warm"].add(warm)
    load = load_average()
    start, start_cpu = time.perf_counter(), time.process_time()
    result = solve_motion(problem, "rrt_connect", seed=case.instance_seed, timeout=timeout)
    whole, whole_cpu = time.perf_counter() - start, time.process_time() - start_cpu
    record.update(success=bool(result.success), posed=True, message=result.message[:200], whole=whole,
                  whole_cpu=whole_cpu, plan=result.planning_time, verify=result.verify_time,
                  min_clearance=result.min_clearance, load_average=float(np.nanmean([load, load_average()])))
    return record


def run(case: Case) -> dict:
    part = case["part"]
    record = {"decompose": _decompose, "cloud_build": _cloud_build, "batched": _batched, "plan": _plan}[part](case)
    record.setdefault("load_average", load_average())
    record.update(cpu_model=cpu_model(), form=case["form"], time=record.get("whole", np.nan), nfe=0)
    return record


# --- summary --------------------------------------------------------------------------------------


def _ms(value: float, fmt: str = ".1f") -> str:
    return "-" if value is None or not np.isfinite(value) else f"{value * 1e3:{fmt}}"


def _plan_tables(rows: list[dict]) -> list[str]:
    lines = []
    for family, group in group_by(rows, "family").items():
        base = {(r["set"], r["problem"]): r["query"] for r in group if r["form"] == "primitives"}
        table = []
        for form in FORMS:
            cases = [r for r in group if r["form"] == form]
            if not cases:
                continue
            wins = [r for r in cases if r["success"]]
            whole = [r["whole"] for r in wins]
            ratio = [r["query"] / base[(r["set"], r["problem"])] for r in cases if (r["set"], r["problem"]) in base]
            cold = [r["build_cold"] for r in cases if "build_cold" in r]
            points = [r["points"] for r in cases if "points" in r]
            table.append([form, f"{len(wins)}/{len(cases)}", str(sum(not r.get("posed", True) for r in cases)),
                          f"{_ms(median(whole))} / {_ms(p95(whole))}", _ms(median(r["whole_cpu"] for r in wins)),
                          _ms(median(r["plan"] for r in wins), ".2f"), _ms(median(r["verify"] for r in wins)),
                          _ms(median(cold)) if cold else "-",
                          _ms(median(r["build_warm"] for r in cases), ".2f"),
                          _ms(median(r["build_structure"] for r in cases), ".2f"),
                          f"{median(r['query'] for r in cases) * 1e9:.0f}", f"{median(ratio):.2f}" if ratio else "-",
                          f"{median(points):,.0f}" if points else "-"])
        robot = group[0]["robot"]
        lines += ["", f"### {family} ({robot}, {len({(r['set'], r['problem']) for r in group})} problems)", ""]
        lines += markdown_table(
            ["obstacles as", "verified", "not posed", "whole call median / p95 [ms]", "whole call CPU median [ms]",
             "planning median [ms]", "verification + retiming median [ms]", "build, cold cache [ms]",
             "build, warm [ms]", "kernel arrays [ms]",
             "batched check [ns/config]", "/ primitives", "cloud points (median)"], table)
    return lines


def summarize(records: list[dict]) -> str:
    ok = finished(records)
    if not ok:
        return "no finished case"
    parts = group_by(ok, "part")
    lines = [cpu_and_load(ok, cpu="cpu_model", digits=2) + "."]
    if "decompose" in parts:
        lines += ["", "### Mesh decomposition (CoACD + cover-excess bound)", ""]
        lines += markdown_table(["mesh", "faces", "pieces", "cover excess [mm]", "cold: wall / CPU [s]",
                                 "cache hit [ms]"],
                                [[r["item"], r["faces"], r["pieces"], f"{r['excess'] * 1e3:.3f}",
                                  f"{r['build_cold']:.2f} / {r['build_cold_cpu']:.2f}", _ms(r["build_warm"], ".2f")]
                                 for r in parts["decompose"]])
    for r in parts.get("cloud_build", []):
        lines += ["", f"### Cloud structure, {r['points']:,} points (median of 7; the entry alone: of 11, "
                      f"interleaved; load average {r.get('load', float('nan')):.1f})", ""]
        lines += markdown_table(["structure", "wall [ms]", "CPU [ms]"], [
            [label, _ms(r[f"{key}_wall"]), _ms(r[f"{key}_cpu"])]
            for label, key in (("obstacle_arrays: the whole shape table of the cloud", "table"),
                               ("the entry alone (grid + tree), compiled core (the table's where built)",
                                "table_compiled"),
                               ("the entry alone, numba kernel", "table_numba"), ("scipy cKDTree", "ckdtree"),
                               ("2 cm distance transform (scipy EDT)", "edt")) if f"{key}_wall" in r])
    for r in parts.get("batched", []):
        lines += ["", f"### Batched check, ten mixed obstacles, capsule Panda, N = {r['n_query']}", ""]
        base = r["query_primitives"]
        lines += markdown_table(["obstacles as", "one call [ns/config]", "20 calls [ns/config]", "/ primitives",
                                 "colliding"], [
            [form, f"{r[f'query_{k}'] * 1e9:.0f}", f"{r[f'query_warm_{k}'] * 1e9:.0f}",
             f"{r[f'query_{k}'] / base:.2f}", f"{100 * r[f'colliding_{k}']:.1f} %"]
            for form in FORMS for k in [form.replace(" ", "_")]])
    plans = [dict(r, family="MotionBenchMaker" if r["set"].startswith("mbm/") else "generated sets")
             for r in parts.get("plan", [])]
    if plans:
        timeouts = ", ".join(f"{t:g}" for t in sorted({r["timeout"] for r in plans}))
        lines += ["", f"### Planning: `solve_motion(problem, \"rrt_connect\")`, {timeouts} s per plan", "",
                  "Whole call = plan + verification + toppra retiming, over the verified motions; build = the "
                  "form's scene from the primitives (meshes: files, decomposition, cover bound; cloud: "
                  "sampling and cropping), kernel arrays = the batched checks' tables (a cloud's grid and "
                  "bounding-box tree); batched check on the same random configurations for every form."]
        lines += _plan_tables(plans)
    lines += ["", "### Anchors (not measured here)", ""]
    lines += markdown_table(["peer", "problems", "build", "query", "planning"], ANCHORS)
    return "\n".join(lines)


study = Study(
    name="obstacle_forms",
    run=run,
    grid=_grid(quick=False),
    quick_grid=_grid(quick=True),
    seed=0,
    fields=Fields(method="form", success="success", time="time", error="time", nfe="nfe",
                  instance=("part", "item", "set", "problem"), group_by=("part",), rank=False, error_unit="s",
                  conditions=f"{TIMEOUT:g} s per plan ({QUICK_TIMEOUT:g} s quick); success = the motion verified "
                             "and retimed by solve_motion"),
    description=(
        "Obstacles as primitives, as triangle meshes (convex pieces with a certified cover bound) and as point "
        "clouds sampled on their surfaces: scene build times, batched-check times, and verified planning on "
        "MotionBenchMaker's problems and our generated sets, per form."),
    summarize=summarize,
    max_workers=1,
)

if __name__ == "__main__":
    from drake_mh.cli import run_script

    run_script(study)
