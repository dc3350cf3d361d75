"""rrt_connect in the compiled core (drake_mh._native.MotionPlanner, C++): its certified-motion
answers and its plans equal the numba kernels' (drake_mh/planning/rrt_connect/search.py) on the
Panda with primitives, meshes, a point cloud and self-collision pairs; what it certifies is free
by Drake's own distances on a fresh plant, sampled densely; bad input raises the planner's
errors."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import DrakeMhError
from drake_mh.planning import MotionProblem, solve_motion
from drake_mh.planning.motion import scene_arguments
from drake_mh.planning.motion import stats as S
from drake_mh.planning.rrt_connect import certify_motions
from drake_mh.planning.rrt_connect import search as K
from drake_mh.planning.rrt_connect.planner import _CLOCK, RRTConnectConfig
from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere
from drake_mh.scene.compiled_check import ENVIRONMENT

pytestmark = pytest.mark.skipif(importlib.util.find_spec("drake_mh._native") is None,
                                reason="the compiled core drake_mh._native is not built (pip install . builds it)")

PANDA = drake_mh.load_robot("panda")
SHAPES = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]
COUNTS = S.T_SAMPLE  # the statistics before the seconds


def cluttered(seed: int) -> Scene:
    """Six obstacles of the four primitive kinds at random poses, link pairs checked."""
    rng = np.random.default_rng(seed)
    scene = Scene(PANDA, self_collision=True)
    for i in range(6):
        scene.add(f"o{i}", SHAPES[i % 4], rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0]), rpy=rng.uniform(-3, 3, 3))
    return scene


def scene_of(form: str) -> Scene:
    if form == "primitives":
        return cluttered(1)
    from drake_mh.scene.benchmark import benchmark_scene

    return benchmark_scene(PANDA, form)


FORMS = ["primitives", "10 mixed as meshes", "10 mixed as a point cloud"]


def planner(scene):
    from drake_mh import _native

    ints, floats, v_WO, reach, lower, upper = scene_arguments(scene)
    return _native.MotionPlanner(ints, floats, reach), (ints, floats, v_WO, reach, lower, upper)


def motions(scene, count: int, seed: int, clearance: float):
    """``count`` motions from free configurations to configurations about 0.5 rad away."""
    rng = np.random.default_rng(seed)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (20 * count, PANDA.nq))
    free = Q[scene.collision_free(Q, clearance, clearance)][:count]
    QB = np.clip(free + rng.normal(0.0, 0.5, free.shape), PANDA.lower, PANDA.upper)
    return np.ascontiguousarray(free), np.ascontiguousarray(QB)


def drake_reference(scene):
    """``f(Q) -> (N,)`` the smallest distance [m] at each configuration by Drake's signed distance
    queries: on a fresh plant over the robot-obstacle pairs and the link pairs the scene checks
    for primitives, else (meshes, a point cloud, which the fresh plant does not take) the scene's
    exact distance (Drake's queries on the scene's own plant, tested against a fresh one in
    tests/scene/test_exact.py)."""
    from pydrake.geometry import Role

    from references import FreshDrake

    if any(type(o.shape).__name__ not in ("Sphere", "Box", "Cylinder", "Capsule") for o in scene.obstacles.values()):
        return scene.exact_min_distance

    drake = FreshDrake(PANDA, scene, self_collision=True)
    inspector = drake.scene_graph.model_inspector()
    world = inspector.world_frame_id()

    def body(geometry):
        frame = inspector.GetFrameId(geometry)
        return None if frame == world else drake.plant.GetBodyFromFrameId(frame).name()

    checked = {frozenset(pair) for pair in scene.self_link_pairs}
    assert inspector.num_geometries() > 0 and Role.kProximity is not None

    def distances(Q):
        out = []
        for q in Q:
            best = np.inf
            for pair in drake.pairs(q, 0.2):
                a, b = body(pair.id_A), body(pair.id_B)
                if a is None or b is None or frozenset((a, b)) in checked:
                    best = min(best, pair.distance)
            out.append(best)
        return np.array(out)

    return distances


def dense(qa, qb, max_step=0.01):
    n = max(1, int(np.ceil(np.max(np.abs(qb - qa)) / max_step)))
    return qa + np.linspace(0.0, 1.0, n + 1)[:, None] * (qb - qa)


@pytest.mark.slow
@pytest.mark.parametrize("form", FORMS)
def test_certified_motions_equal_the_numba_kernels(form):
    """The same booleans and the same counts on random motions, at two clearances; every motion
    the compiled core certifies is free by Drake on a dense sampling (5 of them per case)."""
    scene = scene_of(form)
    native, (ints, floats, v_WO, reach, lower, upper) = planner(scene)
    reference = drake_reference(scene)
    for clearance, seed in ((0.0, 0), (0.01, 1)):
        QA, QB = motions(scene, 150, seed, clearance)
        numba_stats, native_stats = np.zeros(len(S.STAT_NAMES)), np.zeros(len(S.STAT_NAMES))
        expected = K.certify_motions(QA, QB, ints, floats, v_WO, reach, clearance, clearance, 16.0, 0.02, 64, 64, 4,
                                     4096, None, _CLOCK, numba_stats)
        got = native.certify_motions(QA, QB, clearance, clearance, 16.0, 0.02, 64, 64, 4, 4096, native_stats)
        assert 0.1 < expected.mean() < 0.9
        np.testing.assert_array_equal(got, expected)
        np.testing.assert_array_equal(native_stats[:COUNTS], numba_stats[:COUNTS])
        assert numba_stats[S.REFINED] > 0  # the refinement ran too
        for i in np.flatnonzero(got)[:5]:
            assert reference(dense(QA[i], QB[i])).min() >= clearance - 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("form", FORMS)
def test_plans_equal_the_numba_kernels(form):
    """Same seed, same path (1e-9), outcome, goal and counts as plan_kernel; every segment of the
    path free by Drake on a dense sampling."""
    scene = scene_of(form)
    native, (ints, floats, v_WO, reach, lower, upper) = planner(scene)
    reference = drake_reference(scene)
    QA, QB = motions(scene, 12, 7, 0.01)
    config = RRTConnectConfig()
    found = 0
    for i in range(4):
        q0, goals = QA[i], np.ascontiguousarray(QA[4 + 2 * i:6 + 2 * i])
        for clearance in (0.0, 0.01):
            numba_stats, native_stats = np.zeros(len(S.STAT_NAMES)), np.zeros(len(S.STAT_NAMES))
            seed = 1000 + i
            expected = K.plan_kernel(q0, goals, lower, upper, ints, floats, v_WO, reach, clearance, clearance,
                                     np.uint64(seed), 5000, np.inf, config._vector, None, numba_stats)
            got = native.plan(q0, goals, lower, upper, clearance, clearance, seed, 5000, np.inf, config._vector,
                              native_stats)
            assert got[1:] == expected[1:]
            assert got[0].shape == expected[0].shape
            np.testing.assert_allclose(got[0], expected[0], rtol=0, atol=1e-9)
            np.testing.assert_array_equal(native_stats[:COUNTS], numba_stats[:COUNTS])
            if got[1] == S.FOUND:
                found += 1
                path = got[0]
                assert np.array_equal(path[0], q0) and np.array_equal(path[-1], goals[got[2]])
                for a, b in zip(path[:-1], path[1:]):
                    assert reference(dense(a, b)).min() >= clearance - 1e-9
    assert found >= 4


@pytest.mark.slow
def test_rrt_connect_plans_through_the_compiled_core(monkeypatch):
    """rrt_connect's plan and certify_motions through the compiled core never reach the numba
    kernels (replaced by None here) and compile nothing; they give the numba path's path for the
    same seed (DRAKE_MH_COMPILED_CORE=0 on a fresh scene), its counts and its answers; solve_motion
    reports them."""
    from drake_mh._support.compilation import compile_seconds
    from drake_mh.planning.rrt_connect import planner

    results = {}
    for switch in ("1", "0"):
        monkeypatch.setenv(ENVIRONMENT, switch)
        scene = cluttered(3)
        QA, QB = motions(scene, 40, 11, 0.01)
        problem = MotionProblem(PANDA, scene, QA[0], QA[1], clearance=0.01)
        with monkeypatch.context() as patch:
            if switch == "1":
                patch.setattr(K, "plan_kernel", None)
                patch.setattr(K, "certify_motions", None)
            before = compile_seconds()
            path, info = planner.plan(problem, QA[1:3], np.random.default_rng(5), None, None)
            certified = certify_motions(scene, QA, QB, 0.01)
            compiled = compile_seconds() - before
            solved = solve_motion(problem, "rrt_connect", seed=5, retime=False)
        results[switch] = path, info, certified, compiled, solved
    (path, info, certified, compiled, solved), (path0, info0, certified0, _, solved0) = results["1"], results["0"]
    assert compiled == 0.0 and info["prepare_time"] >= 0.0
    assert path is not None and path0 is not None and info["goal"] == info0["goal"]
    np.testing.assert_allclose(path, path0, rtol=0, atol=1e-9)
    for name in S.STAT_NAMES[:COUNTS]:
        assert info[name] == info0[name], name
    assert 0.1 < certified0.mean() < 0.9
    np.testing.assert_array_equal(certified, certified0)
    assert solved.success and solved0.success
    np.testing.assert_allclose(solved.path, solved0.path, rtol=0, atol=1e-9)
    assert solved.info["motions"] == solved0.info["motions"]


def test_bad_input_raises_the_planners_errors():
    """The planner validates in Python before the compiled call: DrakeMhError with the option or
    argument named (and the compiled entry rejects shapes it cannot read, never crashes)."""
    scene = cluttered(4)
    QA, QB = motions(scene, 2, 3, 0.0)
    problem = MotionProblem(PANDA, scene, QA[0], QA[1])
    with pytest.raises(DrakeMhError, match="lanes"):
        solve_motion(problem, "rrt_connect", lanes=0)
    with pytest.raises(DrakeMhError, match="probes"):
        solve_motion(problem, "rrt_connect", probes=9)
    with pytest.raises(DrakeMhError, match="step"):
        solve_motion(problem, "rrt_connect", step=float("nan"))
    with pytest.raises(DrakeMhError):
        certify_motions(scene, QA[:1], np.full((1, PANDA.nq), np.nan))
    with pytest.raises(DrakeMhError, match="hold as many"):
        certify_motions(scene, QA, QB[:1])
    native, (ints, floats, v_WO, reach, lower, upper) = planner(scene)
    stats = np.zeros(len(S.STAT_NAMES))
    options = RRTConnectConfig()._vector
    with pytest.raises(ValueError):
        native.plan(PANDA.home[:3], PANDA.home[None], lower, upper, 0.0, 0.0, 0, 10, 1.0, options, stats)
    with pytest.raises(ValueError):
        native.plan(PANDA.home, PANDA.home[None], lower, upper, 0.0, 0.0, 0, 10, 1.0, options[:3], stats)
    with pytest.raises(ValueError):
        native.certify_motions(PANDA.home[None], np.full((1, PANDA.nq), np.inf), 0.0, 0.0, 16.0, 0.02, 64, 64, 4, 16,
                               stats)
    with pytest.raises(ValueError, match="collision model"):
        type(native)(ints[:-1], floats, reach)
