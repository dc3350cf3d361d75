"""The compiled core (drake_mh._native, C++): its sphere-model check gives the numba kernels'
boolean answers, batched and one configuration at a time, on random and near-contact
configurations of scenes with every primitive kind, with self-collision, with meshes and with a
point cloud; its batched forward kinematics gives Drake's poses and Jacobians."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

import drake_mh
from drake_mh.scene import Box, Capsule, Cylinder, Scene, Sphere

pytestmark = pytest.mark.skipif(importlib.util.find_spec("drake_mh._native") is None,
                                reason="the compiled core drake_mh._native is not built (pip install . builds it)")

PANDA = drake_mh.load_robot("panda")
SHAPES = [Sphere(0.08), Box((0.3, 0.2, 0.05)), Cylinder(0.05, 0.4), Capsule(0.04, 0.3)]
CLEARANCES = [(0.0, 0.0), (0.01, 0.0), (0.05, 0.01), (0.1, 0.02)]


def native():
    from drake_mh import _native

    return _native


def cluttered(seed: int, self_collision: bool) -> Scene:
    """Ten obstacles of the four primitive kinds at random poses in the Panda's reach."""
    rng = np.random.default_rng(seed)
    scene = Scene(PANDA, self_collision=self_collision)
    for i in range(10):
        scene.add(f"o{i}", SHAPES[i % 4], rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.0]), rpy=rng.uniform(-3, 3, 3))
    return scene


def checkers(scene: Scene):
    """``(numba batch, numba one-configuration entry and buffer, native checker)`` of the scene."""
    model = scene.collision_model
    ints, floats = model.packed(scene.obstacle_arrays, model.pair_arrays)
    batch = model.free_function(scene.obstacle_arrays)
    entry, buffer = batch.make_one()
    return batch, entry, buffer, native().CollisionChecker(ints, floats)


def near_contact(batch, Q_free, Q_hit, clearance, self_clearance):
    """Configurations within 1e-9 of the boundary of the numba kernel's free set, on each segment
    from a free configuration to a colliding one (bisection), and a few steps either side."""
    lo, hi = np.zeros(len(Q_free)), np.ones(len(Q_free))
    for _ in range(40):
        t = (lo + hi) / 2
        free = batch(np.ascontiguousarray(Q_free + t[:, None] * (Q_hit - Q_free)), clearance, self_clearance)
        lo, hi = np.where(free, t, lo), np.where(free, hi, t)
    steps = np.array([-1e-6, -1e-9, 0.0, 1e-9, 1e-6])
    t = (lo[:, None] + steps[None, :]).ravel()
    D = np.repeat(Q_hit - Q_free, len(steps), axis=0)
    return np.ascontiguousarray(np.repeat(Q_free, len(steps), axis=0) + t[:, None] * D)


@pytest.mark.parametrize("self_collision", [False, True])
@pytest.mark.parametrize("seed", [1, 2])
def test_native_check_gives_the_numba_answers(seed, self_collision):
    scene = cluttered(seed, self_collision)
    batch, entry, buffer, checker = checkers(scene)
    rng = np.random.default_rng(seed)
    Q = rng.uniform(PANDA.lower, PANDA.upper, (700, PANDA.nq))  # not a multiple of the block size
    for clearance, self_clearance in CLEARANCES:
        c, sc = max(clearance, 1e-12), max(self_clearance, 1e-12)  # as Scene.collision_free passes them
        expected = batch(Q, c, sc)
        assert 0.05 < expected.mean() < 0.95  # both answers occur
        np.testing.assert_array_equal(checker.free(Q, c, sc), expected)
        for N in (1, 3, 129):  # partial blocks
            np.testing.assert_array_equal(checker.free(np.ascontiguousarray(Q[:N]), c, sc), expected[:N])
        for q in Q[:150]:
            assert checker.free_one(q, clearance, self_clearance) == entry(q, clearance, self_clearance, buffer)
        # near contact: configurations on either side of the boundary, within 1e-9 of it
        free = np.flatnonzero(expected)[:40]
        hit = np.flatnonzero(~expected)[:40]
        n = min(len(free), len(hit))
        B = near_contact(batch, Q[free[:n]], Q[hit[:n]], c, sc)
        expected_B = batch(B, c, sc)
        assert 0.2 < expected_B.mean() < 0.8
        np.testing.assert_array_equal(checker.free(B, c, sc), expected_B)
        assert [checker.free_one(b, clearance, self_clearance) for b in B[::7]] == \
            [entry(np.ascontiguousarray(b), clearance, self_clearance, buffer) for b in B[::7]]


def test_native_free_configurations_are_free_by_drake():
    """What the compiled check accepts, Drake's exact distance on the scene's own plant accepts."""
    scene = cluttered(3, True)
    checker = checkers(scene)[3]
    Q = np.random.default_rng(3).uniform(PANDA.lower, PANDA.upper, (60, PANDA.nq))
    free = checker.free(Q, 1e-12, 1e-12)
    assert free.any() and not free.all()
    for q in Q[free]:
        assert scene.min_distance(q) >= 0.0


def test_native_check_reports_bad_input():
    scene = cluttered(1, False)
    checker = checkers(scene)[3]
    Q = np.random.default_rng(0).uniform(PANDA.lower, PANDA.upper, (5, PANDA.nq))
    Q[3, 2] = np.nan
    assert checker.free(Q, 0.01, 0.01) is None
    assert checker.free_one(Q[3], 0.0, 0.0) == -1
    assert checker.free_one(Q[0], -1.0, 0.0) == -2
    assert checker.free_one(Q[0], 0.0, np.inf) == -2
    assert checker.free_one(Q[0, :4], 0.0, 0.0) == -3
    with pytest.raises(ValueError, match="Q must have shape"):
        checker.free(np.ascontiguousarray(Q[:, :4]), 0.01, 0.01)
    model = scene.collision_model
    ints, floats = model.packed(scene.obstacle_arrays, model.pair_arrays)
    with pytest.raises(ValueError, match="do not hold a collision model"):
        native().CollisionChecker(ints[:-1], floats)


@pytest.mark.parametrize("form", ["10 mixed as meshes", "10 mixed as a point cloud"])
def test_native_check_gives_the_numba_answers_for_meshes_and_clouds(form):
    """Convex pieces of meshes and a point cloud (their data in the shape table)."""
    from drake_mh.scene.benchmark import benchmark_scene

    scene = benchmark_scene(PANDA, form)
    batch, entry, buffer, checker = checkers(scene)
    Q = np.random.default_rng(5).uniform(PANDA.lower, PANDA.upper, (300, PANDA.nq))
    for clearance in (0.0, 0.02, 0.1):
        c = max(clearance, 1e-12)
        expected = batch(Q, c, c)
        assert 0.05 < expected.mean() < 0.95
        np.testing.assert_array_equal(checker.free(Q, c, c), expected)
        for q in Q[:100]:
            assert checker.free_one(q, clearance, clearance) == entry(q, clearance, clearance, buffer)
        free, hit = np.flatnonzero(expected)[:20], np.flatnonzero(~expected)[:20]
        n = min(len(free), len(hit))
        B = near_contact(batch, Q[free[:n]], Q[hit[:n]], c, c)
        expected_B = batch(B, c, c)
        assert 0.2 < expected_B.mean() < 0.8
        np.testing.assert_array_equal(checker.free(B, c, c), expected_B)


@pytest.mark.parametrize("name", ["panda", "prismatic chain", "tree"])
def test_native_kinematics_gives_drakes_poses_and_jacobians(name):
    from drake_mh.robot import Robot
    from random_models import random_chain_urdf

    robot = {"panda": lambda: PANDA,
             "prismatic chain": lambda: Robot(random_chain_urdf(7, 3, prismatic_every=2)),
             "tree": lambda: Robot(random_chain_urdf(4, seed=7, branch=True), ee_frame="tip")}[name]()
    bk = robot.batch
    parent, KR, Kp, perm, kind, qidx = bk.chain_arrays
    kin = native().Kinematics(np.concatenate([parent, perm.ravel(), kind, qidx]).astype(np.int64),
                              np.concatenate([KR.ravel(), Kp.ravel()]))
    assert kin.nq == robot.nq
    Q = robot.random_configurations(70, 4)
    Q[0, 0] += 2e5  # an angle beyond the polynomial's reduction: the C library's sine
    for frame in [None] + (["b1_link"] if name == "tree" else []):
        anchor, ER, Ep, on_path = bk.frame_arrays(frame)
        T, J = kin.fk_jacobian(Q, anchor, np.ascontiguousarray(ER.ravel()), Ep, on_path, True)
        T_only, none = kin.fk_jacobian(Q, anchor, np.ascontiguousarray(ER.ravel()), Ep, on_path, False)
        assert none is None
        np.testing.assert_array_equal(T_only, T)
        for n, q in enumerate(Q):
            np.testing.assert_allclose(T[n], robot.fk_drake(q, frame), atol=1e-10, rtol=0)
            np.testing.assert_allclose(J[n], robot.jacobian_drake(q, frame), atol=1e-10, rtol=0)
    R, p = kin.moving_frames(Q)
    R_ref, p_ref = bk.moving_frames(Q)
    np.testing.assert_allclose(R, R_ref, atol=1e-12, rtol=0)
    np.testing.assert_allclose(p, p_ref, atol=1e-12, rtol=0)
