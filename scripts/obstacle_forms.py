"""Mesh and point-cloud obstacles: build times, query times and planning, against primitives.

A small measuring script, not a study (``studies/`` holds :class:`drake_mh.study.Study` grids;
the full integration into ``studies/motion_benchmark.py`` is a follow-up). It prints, with the CPU model and the load
average:

1. **Decomposition**: CoACD and the cover-excess bound per test mesh (``tests/data/``) from an
   empty cache, then the cache hit (wall and CPU seconds, pieces, excess).
2. **Cloud structure build at 50,000 points**: the kernels' implicit k-d tree (with the shape
   table it goes in), beside scipy's ``cKDTree`` and a 2 cm Euclidean distance transform over
   the cloud's bounding box (scipy's ``distance_transform_edt``): the candidates of the choice.
3. **Batched check** (``Scene.collision_free``, N = 1024, ns per configuration, interleaved
   rounds, median; warm = 20 consecutive calls) on the shared benchmark scene as primitives,
   as meshes and as a 50,000-point cloud sampled on the same surfaces
   (:mod:`drake_mh.scene.benchmark`).
4. **Planning**: ``rrt_connect`` on one generated problem set (:func:`problem_set`), the
   obstacles given as primitives, as meshes, and as point clouds sampled on their surfaces
   (1 point per cm², radius 0): verified success and whole-call time (plan + verification +
   retiming) per form.

Run: ``python scripts/obstacle_forms.py [--quick]``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


def _timed(function, rounds: int = 1):
    """Median wall and CPU seconds (:func:`collision_speed._timed`, the same method)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
    from collision_speed import _timed as timed

    return timed(function, rounds)


def decomposition() -> list[str]:
    from drake_mh._support.cache import temporary_cache
    from drake_mh.geometry.convex_pieces import convex_pieces
    from drake_mh.scene import Mesh

    lines = ["| mesh | faces | pieces | cover excess [mm] | made: wall / CPU [s] | cache hit [ms] |", "|---|---|---|---|---|---|"]
    with temporary_cache():
        for name in ("bin.obj", "bracket.obj", "cube.stl"):
            mesh = Mesh(DATA / name)
            convex_pieces.cache_clear()
            made = _timed(lambda: convex_pieces(mesh))
            pieces = convex_pieces(mesh)
            convex_pieces.cache_clear()
            hit = _timed(lambda: (convex_pieces.cache_clear(), convex_pieces(mesh)), 5)
            lines.append(f"| {name} | {len(mesh.faces)} | {len(pieces)} | {pieces.excess * 1e3:.3f} | "
                         f"{made[0]:.1f} / {made[1]:.1f} | {hit[0] * 1e3:.2f} |")
    return lines


def cloud_build(n: int = 50_000) -> list[str]:
    from scipy import ndimage
    from scipy.spatial import cKDTree

    from drake_mh.geometry.cloud import PointCloud
    from drake_mh.scene.batch import _cloud_rows
    from drake_mh.scene.kernels.pieces import CLOUD, kd_build
    from drake_mh.scene.benchmark import benchmark_scene

    rng = np.random.default_rng(0)
    points = rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0], (n, 3))
    cloud = PointCloud(points, 0.0)
    kd_build(points[:100])  # compiled before the clock

    def edt():
        lo = points.min(axis=0)
        cells = np.floor((points - lo) / 0.02).astype(np.int64)
        grid = np.ones(cells.max(axis=0) + 1, bool)
        grid[tuple(cells.T)] = False
        ndimage.distance_transform_edt(grid)

    rows = [("kernel k-d tree (tree only)", lambda: kd_build(points)),
            ("kernel k-d tree + shape table", lambda: _cloud_rows(cloud, np.eye(3), np.zeros(3), CLOUD)),
            ("scipy cKDTree", lambda: cKDTree(points)),
            ("2 cm distance transform (scipy EDT)", edt)]
    lines = [f"| structure, {n} points | wall [ms] | CPU [ms] |", "|---|---|---|"]
    for label, function in rows:
        wall, cpu = _timed(function, 7)
        lines.append(f"| {label} | {wall * 1e3:.1f} | {cpu * 1e3:.1f} |")
    del benchmark_scene
    return lines


def batched(quick: bool) -> list[str]:
    import drake_mh
    from drake_mh.scene.benchmark import BENCHMARK_SCENES, benchmark_scene

    robot = drake_mh.load_robot("panda")
    kinds = BENCHMARK_SCENES[1:]
    scenes = {kind: benchmark_scene(robot, kind) for kind in kinds}
    rng = np.random.default_rng(0)
    Q = robot.random_configurations(256 if quick else 1024, rng=rng)
    for scene in scenes.values():
        scene.collision_free(Q)  # compile / bind first
    samples = {kind: [] for kind in kinds}
    warm = {kind: [] for kind in kinds}
    for _ in range(3 if quick else 9):
        for kind, scene in scenes.items():
            samples[kind].append(_timed(lambda: scene.collision_free(Q)))
            warm[kind].append(_timed(lambda: [scene.collision_free(Q) for _ in range(20)]))
    base = np.median([w for w, _ in samples[kinds[0]]])
    lines = ["| scene | collision_free [ns/config] (CPU) | warm, 20 calls [ns/config] | / primitives | colliding |",
             "|---|---|---|---|---|"]
    for kind, scene in scenes.items():
        wall = np.median([w for w, _ in samples[kind]])
        cpu = np.median([c for _, c in samples[kind]])
        hot = np.median([w for w, _ in warm[kind]]) / 20
        lines.append(f"| {kind} | {wall / len(Q) * 1e9:.0f} ({cpu / len(Q) * 1e9:.0f}) | {hot / len(Q) * 1e9:.0f} | "
                     f"{wall / base:.2f} | {1 - scene.collision_free(Q).mean():.1%} |")
    return lines


def _forms(problem, cloud_density: float = 1e4):
    """The problem's scene as primitives (itself), as meshes, and as a surface point cloud."""
    import trimesh
    from pydrake.math import RotationMatrix

    from drake_mh._support.cache import atomic_write_bytes, cache_dir
    from drake_mh.geometry.mesh import obj_bytes
    from drake_mh.planning import MotionProblem
    from drake_mh.scene import Mesh, PointCloud, Scene
    from drake_mh.scene.benchmark import primitive_mesh

    robot, scene = problem.robot, problem.scene
    meshes, clouds = Scene(robot, self_collision=scene.self_collision), Scene(robot, self_collision=scene.self_collision)
    points = []
    for name, obstacle in scene.obstacles.items():
        mesh = primitive_mesh(obstacle.shape)
        data = obj_bytes(mesh.vertices, mesh.faces, f"{name}")
        path = cache_dir("benchmark_meshes") / f"{abs(hash(data))}.obj"
        if not path.is_file():
            atomic_write_bytes(path, data)
        rpy = RotationMatrix(obstacle.X_WO[:3, :3]).ToRollPitchYaw().vector()
        meshes.add(name, Mesh(path), obstacle.position, rpy=rpy)
        local, _ = trimesh.sample.sample_surface(mesh, max(1, int(mesh.area * cloud_density)), seed=1)
        points.append(np.asarray(local) @ obstacle.X_WO[:3, :3].T + obstacle.position)
    clouds.add("cloud", PointCloud(np.vstack(points), 0.0))
    out = {"primitives": problem}
    for label, form in (("meshes", meshes), ("point cloud", clouds)):
        try:
            out[label] = MotionProblem(robot, form, problem.q_start, problem.goal_configurations, problem.clearance,
                                       problem.self_clearance, name=problem.name)
        except Exception as exc:  # start or goal not free under this form: counted as such
            out[label] = exc
    return out


def planning(quick: bool, set_name: str = "table_pick") -> list[str]:
    from drake_mh.planning import solve_motion
    from drake_mh.planning.problems import problem_set

    problems = problem_set(set_name, "panda", count=3 if quick else 10, seed=0)
    results = {"primitives": [], "meshes": [], "point cloud": []}
    for problem in problems:
        for label, form in _forms(problem).items():
            if isinstance(form, Exception):
                results[label].append((False, np.nan, np.nan, f"not posed: {form}"))
                continue
            solve_motion(form, "rrt_connect", seed=0, retime=False)  # compile / bind (kept warm)
            start = time.perf_counter()
            result = solve_motion(form, "rrt_connect", seed=1, timeout=10.0)
            whole = time.perf_counter() - start
            results[label].append((bool(result.success), whole, result.planning_time, result.message))
    lines = [f"rrt_connect on {set_name} ({len(problems)} problems, capsule Panda):", "",
             "| obstacles as | success | whole call median [ms] | planning median [ms] |", "|---|---|---|---|"]
    for label, rows in results.items():
        ok = [r for r in rows if r[0]]
        lines.append(f"| {label} | {len(ok)}/{len(rows)} | {np.median([r[1] for r in ok]) * 1e3 if ok else np.nan:.1f} | "
                     f"{np.median([r[2] for r in ok]) * 1e3 if ok else np.nan:.2f} |")
    return lines


def main(quick: bool = False) -> None:
    from drake_mh.study.machine import cpu_model, load_average

    print(f"CPU: {cpu_model()}; load average {load_average():.1f}\n")
    for part in (decomposition(), cloud_build(), batched(quick), planning(quick)):
        print("\n".join(part), "\n", flush=True)
    print(f"load average at the end: {load_average():.1f}")


if __name__ == "__main__":
    main("--quick" in sys.argv[1:])
