"""The compiled core's clearance values and certified segments (``drake_mh._native.Clearances``,
cpp/clearances.hpp and cpp/segments.hpp) against the numba kernels they port
(:func:`drake_mh.scene.kernels.collision.link_clearances`,
:func:`drake_mh.scene.kernels.segments.certify_segments`), and what they certify against Drake's
own distance on a fresh plant. Skipped where the core is not built."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import drake_mh
from drake_mh.planning.problems import load_problem_robot
from drake_mh.scene import Box, Capsule, Cylinder, Mesh, PointCloud, Scene, Sphere
from drake_mh.scene.benchmark import mesh_file
from drake_mh.scene.kernels import collision as K
from drake_mh.scene.kernels import segments as SK
from drake_mh.scene.segments import MIN_PIECE
from references import FreshDrake, dense_path

pytestmark = pytest.mark.skipif(importlib.util.find_spec("drake_mh._native") is None,
                                reason="the compiled core (drake_mh._native) is not built: pip install builds it")

PANDA = drake_mh.load_robot("panda")


@pytest.fixture(scope="module")
def hand():
    return load_problem_robot("panda_hand_mbm")


def every_kind(robot, seed: int, mesh: bool = True) -> Scene:
    """Self-collision on; two of each primitive kind, a box as a mesh (its convex pieces; not with
    ``mesh=False``: the segments' curvature bound then applies) and a point cloud of 400 balls
    (1 cm), at random poses in the arm's reach."""
    rng = np.random.default_rng(seed)
    scene = Scene(robot, self_collision=True)
    shapes = [Sphere(0.08), Box([0.1, 0.15, 0.05]), Cylinder(0.06, 0.3), Capsule(0.05, 0.2)]
    for i in range(8):
        scene.add(f"o{i}", shapes[i % 4], rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 0.9]), rpy=rng.uniform(-3, 3, 3))
    where = rng.uniform([-0.6, -0.6, 0.2], [0.6, 0.6, 0.8]), rng.uniform(-3, 3, 3)
    if mesh:
        scene.add("mesh", Mesh(mesh_file(Box([0.1, 0.2, 0.15]))), where[0], rpy=where[1])
    centre = rng.uniform([-0.5, -0.5, 0.3], [0.5, 0.5, 0.7])
    scene.add("cloud", PointCloud(centre + rng.uniform(-0.15, 0.15, (400, 3)), 0.01))
    return scene


def numba_values(model, obstacles, v_WO, Q, tau, fine_below, pair_fine, mode) -> np.ndarray:
    pairs = model.no_pair_arrays if mode != K.PER_LINK else model.pair_arrays
    kinds, R_WO, p_WO, _, dims = obstacles
    width = model.num_links + model.num_pairs if mode == K.PER_LINK else len(kinds) if mode == K.PER_OBSTACLE else 1
    out = np.empty((len(Q), width))
    K.link_clearances(np.ascontiguousarray(Q.T), tau, fine_below, pair_fine, mode, *model._kernel_args(), kinds,
                      R_WO, p_WO, v_WO, dims, *pairs, out)
    return out


def numba_certificate(model, obstacles, v_WO, QA, QB, speed, clearance, self_clearance, tolerance) -> tuple:
    kinds, R_WO, p_WO, _, dims = obstacles
    M = len(QA)
    out = (np.empty(M, np.int64), np.empty(M), np.empty(M), np.empty(M), np.empty(M, np.int64))
    SK.certify_segments(QA, QB, model.reach, speed, clearance, self_clearance, tolerance, MIN_PIECE, 1 << 16,
                        *model._kernel_args(), kinds, R_WO, p_WO, v_WO, dims, *model.pair_arrays, *out)
    return out


@pytest.mark.parametrize("which", ["panda", "hand"])
def test_clearance_values_are_the_numba_kernels(which, hand):
    """Every mode (per link and pair with finite and infinite fine_below, some pairs at -inf; per
    obstacle; overall), obstacles moving (v_WO nonzero, tau per configuration) and standing: the
    same values to 1e-9 on 300 random configurations (and on 1 and 129: a lane block's edges)."""
    robot = PANDA if which == "panda" else hand
    scene = every_kind(robot, 3)
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    assert set(obstacles[0]) == {0, 1, 2, 3, 4, 5} and model.num_pairs > 0
    assert np.any(model.pair_arrays[2][:, 0] > 0) or which == "panda"  # the hand's pairs have floor tables
    rng = np.random.default_rng(4)
    Q = robot.random_configurations(300, rng=rng)
    tau = rng.uniform(0.0, 1.0, len(Q))
    moving = rng.normal(0.0, 0.2, obstacles[3].shape)
    for v_WO in (np.zeros_like(moving), moving):
        for mode, fine in ((K.PER_LINK, 0.05), (K.PER_LINK, np.inf), (K.PER_OBSTACLE, np.inf), (K.OVERALL, np.inf)):
            compiled = model.compiled_clearances(obstacles, pairs=mode == K.PER_LINK)
            pair_fine = np.full(model.num_pairs if mode == K.PER_LINK else 0, fine)
            pair_fine[::3] = -np.inf
            for N in (1, 129, 300):
                expected = numba_values(model, obstacles, v_WO, Q[:N], tau[:N], fine, pair_fine, mode)
                got = compiled.values(Q[:N], tau[:N], fine, pair_fine, mode, v_WO)
                assert got.shape == expected.shape
                np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-9)
            if mode == K.PER_LINK and fine < np.inf:
                assert np.sum(expected[:, :model.num_links] < fine) > 50  # fine spheres were used
                assert np.sum(expected[:, :model.num_links] >= fine) > 50  # and bounds


def scene_and_core(robot, seed: int, mesh: bool) -> tuple:
    """``(scene, model, obstacles, compiled)``: :func:`every_kind` and its compiled clearances with
    the link pairs."""
    scene = every_kind(robot, seed, mesh)
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    return scene, model, obstacles, model.compiled_clearances(obstacles, pairs=True)


def compiled_one_by_one(compiled, model, v_WO, QA, QB, speed, clearance, self_clearance, tolerance) -> tuple:
    """The compiled certificate of each segment in a call of its own (its batches then hold only
    its own configurations, as the numba kernel's do)."""
    rows = [compiled.certify_segments(QA[i:i + 1], QB[i:i + 1], model.reach, v_WO, speed, clearance, self_clearance,
                                      tolerance, MIN_PIECE, 1 << 16) for i in range(len(QA))]
    return tuple(np.concatenate([r[k] for r in rows]) for k in range(5))


@pytest.mark.parametrize("mesh", [True, False])
@pytest.mark.parametrize("which", ["panda", "hand"])
def test_certified_segments_are_the_numba_verdicts(which, hand, mesh):
    """60 random segments (short and long), obstacles standing and moving, certification only and
    with a tolerance, each segment in a call of its own, with a mesh (the Lipschitz bound alone)
    and without (the curvature bound too): the same status and evaluations, t_stop and the lower
    bounds to 1e-9; both verdicts occur."""
    robot = PANDA if which == "panda" else hand
    scene, model, obstacles, compiled = scene_and_core(robot, 5, mesh)
    rng = np.random.default_rng(6)
    Q = robot.random_configurations(400, rng=rng)
    QA = Q[scene.collision_free(Q, 0.0, 0.002)][:60]
    QB = np.clip(QA + rng.normal(0.0, 1.0, QA.shape) * rng.choice([0.05, 0.3, 1.0], (len(QA), 1)),
                 robot.lower, robot.upper)
    moving = rng.normal(0.0, 0.05, obstacles[3].shape)
    seen = set()
    for v_WO in (np.zeros_like(moving), moving):
        speed = float(np.max(np.linalg.norm(v_WO, axis=1)))
        for clearance, self_clearance, tolerance in ((0.0, 0.002, np.inf), (0.01, 0.0, 1e-3)):
            expected = numba_certificate(model, obstacles, v_WO, QA, QB, speed, clearance, self_clearance, tolerance)
            got = compiled_one_by_one(compiled, model, v_WO, QA, QB, speed, clearance, self_clearance, tolerance)
            np.testing.assert_array_equal(got[0], expected[0])
            np.testing.assert_array_equal(got[4], expected[4])
            for x, y in zip(got[1:4], expected[1:4]):
                np.testing.assert_allclose(x, y, rtol=0.0, atol=1e-9)  # NaN where the other is NaN
            seen.update(expected[0].tolist())
    assert {SK.CERTIFIED, SK.BLOCKED} <= seen


@pytest.mark.parametrize("mesh", [True, False])
@pytest.mark.parametrize("which", ["panda", "hand"])
def test_segments_certified_together_keep_each_verdict(which, hand, mesh):
    """One call on many segments (a path: each starts where the last ended, and unrelated ones)
    evaluates their configurations in shared batches. A value above the fine level is a lower
    bound that may depend on its batch, so the evaluations may differ from one call per segment;
    the statuses do not, and every certified lower bound stays below the sphere model's exact
    clearance at 1,001 configurations of its segment."""
    robot = PANDA if which == "panda" else hand
    scene, model, obstacles, compiled = scene_and_core(robot, 3, mesh)
    rng = np.random.default_rng(11)
    Q = robot.random_configurations(600, rng=rng)
    Q = Q[scene.collision_free(Q, 0.0, 0.002)]
    path = np.clip(Q[0] + np.cumsum(rng.normal(0.0, 0.15, (25, robot.nq)), axis=0), robot.lower, robot.upper)
    QA = np.vstack([path[:-1], Q[1:21]])
    QB = np.vstack([path[1:], np.clip(Q[1:21] + rng.normal(0.0, 0.5, (20, robot.nq)), robot.lower, robot.upper)])
    v_WO = np.zeros_like(obstacles[3])
    t = np.linspace(0.0, 1.0, 1001)
    seen = set()
    for clearance, self_clearance, tolerance in ((0.0, 0.002, np.inf), (0.01, 0.0, 1e-3)):
        alone = compiled_one_by_one(compiled, model, v_WO, QA, QB, 0.0, clearance, self_clearance, tolerance)
        together = compiled.certify_segments(QA, QB, model.reach, v_WO, 0.0, clearance, self_clearance, tolerance,
                                             MIN_PIECE, 1 << 16)
        np.testing.assert_array_equal(together[0], alone[0])
        seen.update(alone[0].tolist())
        for i in np.flatnonzero(together[0] == SK.CERTIFIED):
            dense = QA[i] + t[:, None] * (QB[i] - QA[i])
            exact = compiled.values(dense, np.zeros(0), np.inf, np.full(model.num_pairs, np.inf), K.PER_LINK, v_WO)
            assert together[2][i] <= np.min(exact[:, :model.num_links]) + 1e-9
            assert together[3][i] <= np.min(exact[:, model.num_links:], initial=np.inf) + 1e-9
            if tolerance < np.inf:  # the links exact everywhere: within the tolerance as alone
                assert abs(together[2][i] - alone[2][i]) <= tolerance
    assert {SK.CERTIFIED, SK.BLOCKED} <= seen


def test_scene_certificates_and_clearances_with_and_without_the_core(monkeypatch):
    """Scene.certify_segments (with a duration: moving obstacles), certify_path with a tolerance and
    batch_obstacle_distances / batch_min_distance with the compiled core and with
    DRAKE_MH_COMPILED_CORE=0 (the numba kernels): the same statuses, path clearances within the
    tolerance of each other (the core batches the segments together: a value above the fine level
    is a lower bound that may depend on its batch) and the same distances to 1e-9."""
    rng = np.random.default_rng(9)
    Q = PANDA.random_configurations(200, rng=rng)
    QA = Q[every_kind(PANDA, 7).collision_free(Q)][:20]
    QB = np.clip(QA + rng.normal(0.0, 0.4, QA.shape), PANDA.lower, PANDA.upper)

    def answers():  # a new scene: its functions bound under the environment as it is
        scene = every_kind(PANDA, 7)
        scene.move("o0", velocity=[0.3, 0.0, -0.2])
        assert (scene.collision_model.compiled_clearances(scene.obstacle_arrays, True) is None) == kernels
        cert = scene.certify_segments(QA, QB, 0.005, 0.002, duration=0.5)
        i = int(np.argmax(scene.certify_segments(QA, QB, 0.0).certified))  # a certified path along a segment
        path = scene.certify_path(QA[i] + np.array([0.0, 0.3, 0.6, 1.0])[:, None] * (QB[i] - QA[i]), 0.0,
                                  tolerance=1e-3)
        assert path.certified
        return cert.status, path.min_clearance, scene.batch_obstacle_distances(Q), scene.batch_min_distance(Q)

    kernels = False
    compiled = answers()
    monkeypatch.setenv("DRAKE_MH_COMPILED_CORE", "0")
    kernels = True
    numba = answers()
    np.testing.assert_array_equal(compiled[0], numba[0])
    assert abs(compiled[1] - numba[1]) <= 1e-3 + 1e-9
    for x, y in zip(compiled[2:], numba[2:]):
        np.testing.assert_allclose(x, y, rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("seed", range(2))
def test_what_the_core_certifies_is_free_by_drake(seed):
    """Segments the compiled core certifies (spheres, boxes, cylinders: Drake's reference kinds),
    sampled at 2 mrad of their fastest joint, keep their certified lower bound by Drake's own
    distance on a fresh plant; at least 6 certified per seed."""
    rng = np.random.default_rng(20 + seed)
    scene = Scene(PANDA)
    shapes = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4)]
    for i in range(6):
        scene.add(f"o{i}", shapes[i % 3], rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 0.9]), rpy=rng.uniform(-3, 3, 3))
    assert scene.collision_model.compiled_clearances(scene.obstacle_arrays, True) is not None
    drake = FreshDrake(PANDA, scene)
    Q = PANDA.random_configurations(300, rng=rng)
    QA = Q[scene.collision_free(Q, 0.01)][:12]
    QB = np.clip(QA + rng.normal(0.0, 0.4, QA.shape), PANDA.lower, PANDA.upper)
    cert = scene.certify_segments(QA, QB, 0.01)
    certified = 0
    for i in np.flatnonzero(cert.certified):
        sampled = drake.min_distances(dense_path(np.stack([QA[i], QB[i]]), 0.002))
        assert sampled.min() >= cert.lower[i] - 1e-9 and cert.lower[i] >= 0.01
        certified += 1
    assert certified >= 6, certified


def test_clearances_reject_bad_buffers_and_shapes():
    """A ValueError naming what is wrong for buffers that are not a model, arrays of wrong shapes
    and non-finite segment ends; None for configurations that are not finite."""
    from drake_mh import _native

    scene = every_kind(PANDA, 1)
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    ints, floats = model.packed(obstacles, model.pair_arrays)
    with pytest.raises(ValueError, match="do not hold a collision model"):
        _native.Clearances(ints[:-1], floats)
    compiled = _native.Clearances(ints, floats)
    v_WO, Q = np.zeros((len(obstacles[0]), 3)), PANDA.random_configurations(3)
    pair_fine = np.zeros(model.num_pairs)
    with pytest.raises(ValueError, match="v_WO"):
        compiled.values(Q, np.zeros(3), 0.05, pair_fine, K.PER_LINK, np.zeros((1, 3)))
    with pytest.raises(ValueError, match="pair_fine_below"):
        compiled.values(Q, np.zeros(3), 0.05, pair_fine[1:], K.PER_LINK, v_WO)
    Q[1, 2] = np.nan
    assert compiled.values(Q, np.zeros(3), 0.05, pair_fine, K.PER_LINK, v_WO) is None
    with pytest.raises(ValueError, match="finite QA"):
        compiled.certify_segments(Q, Q, model.reach, v_WO, 0.0, 0.0, 0.0, np.inf, MIN_PIECE, 100)


def test_models_keep_the_buffers_they_borrow_alive():
    """The compiled models read the packed buffers in place (no copy): built from arrays whose
    only other references are then dropped, they answer as a model on the live arrays does."""
    import gc

    from drake_mh import _native
    from drake_mh.planning.rrt_connect.planner import compiled_planner

    scene = every_kind(PANDA, 1)
    model, obstacles = scene.collision_model, scene.obstacle_arrays
    ints, floats = model.packed(obstacles, model.pair_arrays)
    v_WO, Q = np.zeros((len(obstacles[0]), 3)), PANDA.random_configurations(64, np.random.default_rng(5))
    pair_fine = np.zeros(model.num_pairs)
    expected = _native.Clearances(ints, floats).values(Q, np.zeros(64), 0.05, pair_fine, K.PER_LINK, v_WO)
    expected_free = _native.CollisionChecker(ints, floats).free(Q, 1e-12, 1e-12)
    copies = (ints.copy(), floats.copy())
    borrowed = _native.Clearances(*copies)
    checker = _native.CollisionChecker(*copies)
    planner = _native.MotionPlanner(*copies, model.reach)
    del copies
    gc.collect()
    junk = [np.full_like(a, -1) for a in (ints, floats) for _ in range(4)]  # reuse freed memory, if any was freed
    np.testing.assert_array_equal(borrowed.values(Q, np.zeros(64), 0.05, pair_fine, K.PER_LINK, v_WO), expected)
    np.testing.assert_array_equal(checker.free(Q, 1e-12, 1e-12), expected_free)
    del borrowed, checker, planner, junk
    gc.collect()
    assert compiled_planner(scene) is not None
