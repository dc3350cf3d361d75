"""BatchKinematics agrees with Drake on every bundled robot, random URDF chains and DH robots, in
the compiled core and in the numba kernels (the fallback where the core is not built)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh._support.native import ENVIRONMENT, compiled_core
from drake_mh.errors import InvalidConfiguration
from drake_mh.robot import Robot

from random_models import random_chain_urdf

TOL = 1e-10
ROBOTS = {name: drake_mh.load_robot(name) for name in drake_mh.available_robots()}


@pytest.fixture(autouse=True, scope="module", params=["core", "numba"])
def backend(request):
    """Every test once with the compiled core and once with the numba kernels."""
    with pytest.MonkeyPatch.context() as patch:
        if request.param == "numba":
            patch.setenv(ENVIRONMENT, "0")
        elif compiled_core() is None:
            pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
        yield request.param


def assert_matches_drake(robot, Q, frame=None):
    T, J = robot.batch.fk_jacobian(Q, frame)
    for q, T_i, J_i in zip(Q, T, J):
        np.testing.assert_allclose(T_i, robot.fk_drake(q, frame), atol=TOL, rtol=0)
        np.testing.assert_allclose(J_i, robot.jacobian_drake(q, frame), atol=TOL, rtol=0)


@pytest.mark.parametrize("name", sorted(ROBOTS))
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_bundled_robots_match_drake(name, seed):
    robot = ROBOTS[name]
    assert_matches_drake(robot, robot.random_configurations(8, seed))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 9), prismatic=st.sampled_from([0, 2, 3]))
def test_random_urdf_chains_match_drake(seed, n, prismatic):
    robot = Robot(random_chain_urdf(n, seed, prismatic_every=prismatic))
    assert_matches_drake(robot, robot.random_configurations(6, seed))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 8),
       convention=st.sampled_from(["standard", "modified"]))
def test_random_dh_robots_match_drake(seed, n, convention):
    rng = np.random.default_rng(seed)
    alpha = rng.choice([0.0, np.pi / 2, -np.pi / 2, np.pi], n) + rng.normal(0, 0.3, n) * rng.integers(0, 2, n)
    robot = Robot.from_dh(rng.uniform(0, 0.5, n), alpha, rng.uniform(0, 0.3, n),
                          offset=rng.uniform(-1, 1, n), convention=convention)
    assert_matches_drake(robot, robot.random_configurations(6, seed))


def test_tree_with_branch_and_other_frames():
    robot = Robot(random_chain_urdf(4, seed=7, branch=True), ee_frame="tip")
    Q = robot.random_configurations(5, 0)
    assert_matches_drake(robot, Q)
    assert_matches_drake(robot, Q, frame="b1_link")  # a frame on the side branch
    J = robot.batch.jacobian(Q, frame="b1_link")
    main_chain = [robot.joint_names.index(f"j{i}") for i in (2, 3)]
    assert np.all(J[:, :, main_chain] == 0.0)  # joints past the branch point do not move it


def test_large_angles_use_the_exact_fallback():
    robot = ROBOTS["panda"]
    Q = robot.random_configurations(4, 1) + np.array([1e6, -3e5, 2e5, 0, 0, 0, 0])
    assert_matches_drake(robot, Q)


def test_points_and_moving_frames():
    robot = ROBOTS["seed000_6dof"]
    Q = robot.random_configurations(7, 2)
    links = robot.link_names()
    offsets = np.random.default_rng(0).normal(size=(len(links), 3))
    P = robot.batch.points(Q, *robot.batch.compile_points(links, offsets))
    for q, P_i in zip(Q, P):
        poses = robot.link_poses(q)
        for link, p_B, p_W in zip(links, offsets, P_i):
            np.testing.assert_allclose(p_W, poses[link][:3, :3] @ p_B + poses[link][:3, 3], atol=TOL)
    R, p = robot.batch.moving_frames(Q)
    J = robot.batch.jacobian(Q)
    np.testing.assert_allclose(R[:, :, :, 2], np.swapaxes(J[:, :3, :], 1, 2), atol=TOL)  # axes


def test_batch_manipulability_and_single_configuration():
    robot = ROBOTS["panda"]
    Q = robot.random_configurations(5, 3)
    np.testing.assert_allclose(robot.batch.manipulability(Q), [robot.manipulability(q) for q in Q], atol=1e-12)
    assert robot.batch.fk(Q[0]).shape == (1, 4, 4)
    np.testing.assert_allclose(robot.batch.positions(Q), robot.batch.fk(Q)[:, :3, 3])


def test_block_boundaries():
    robot = ROBOTS["planar5"]
    for N in (63, 64, 65, 129):  # around the kernels' block size
        Q = robot.random_configurations(N, N)
        T = robot.batch.fk(Q)
        np.testing.assert_allclose(T[-1], robot.fk_drake(Q[-1]), atol=TOL)
        np.testing.assert_allclose(T[0], robot.fk_drake(Q[0]), atol=TOL)


def test_sphere_centres_follow_their_links():
    robot = ROBOTS["panda"]
    model = robot.sphere_model
    Q = robot.random_configurations(4, 5)
    C = robot.batch.sphere_centres(Q)
    assert C.shape == (4, model.num_spheres, 3)
    for q, C_i in zip(Q, C):
        poses = robot.link_poses(q)
        expected = [poses[link][:3, :3] @ c + poses[link][:3, 3] for link, c in zip(model.links, model.centres_B)]
        np.testing.assert_allclose(C_i, expected, atol=TOL)


def test_single_configuration_matches_drake_and_refuses_non_finite():
    robot = ROBOTS["panda"]
    for q in robot.random_configurations(5, 9):
        np.testing.assert_allclose(robot.batch.one(q), robot.fk_drake(q), atol=TOL, rtol=0)
        np.testing.assert_allclose(robot.batch.one(list(q), want_jac=True), robot.jacobian_drake(q), atol=TOL, rtol=0)
        np.testing.assert_allclose(robot.batch.one(q[::-1][::-1].copy()[::1]), robot.fk_drake(q), atol=TOL, rtol=0)
    q = robot.home.copy()
    q[3] = np.nan
    for want_jac in (False, True):
        with pytest.raises(InvalidConfiguration, match="NaN|finite|inf"):
            robot.batch.one(q, want_jac=want_jac)
