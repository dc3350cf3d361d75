"""BatchDynamics (plant-compiled RNEA, in the compiled core and in the numba fallback) against Drake's
inverse dynamics with gravity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh._support.native import ENVIRONMENT, compiled_core
from drake_mh.errors import InvalidArgument
from drake_mh.robot import Robot
from drake_mh.trajectories import BatchDynamics


def _random_urdf(n: int, seed: int, prismatic_every: int = 0) -> str:
    """A chain with random joint poses and axes, and off-centre masses with full inertia tensors."""
    rng = np.random.default_rng(seed)
    parts = ['<?xml version="1.0"?>', '<robot name="rnd">', '<link name="base"/>']
    parent = "base"
    for i in range(n):
        kind = "prismatic" if prismatic_every and i % prismatic_every == prismatic_every - 1 else "revolute"
        xyz, rpy, com, crpy = (rng.uniform(-0.3, 0.3, 3), rng.uniform(-np.pi, np.pi, 3),
                               rng.uniform(-0.1, 0.1, 3), rng.uniform(-np.pi, np.pi, 3))
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        d = rng.uniform(0.01, 0.05, 3)
        ixx, iyy, izz = d[1] + d[2], d[0] + d[2], d[0] + d[1]  # triangle inequality holds
        parts.append(
            f'<link name="l{i}"><inertial><origin xyz="{com[0]} {com[1]} {com[2]}" '
            f'rpy="{crpy[0]} {crpy[1]} {crpy[2]}"/><mass value="{rng.uniform(0.5, 3)}"/>'
            f'<inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" ixy="0" ixz="0" iyz="0"/></inertial></link>'
            f'<joint name="j{i}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>'
            f'<axis xyz="{axis[0]} {axis[1]} {axis[2]}"/>'
            f'<limit lower="-2" upper="2" velocity="1" effort="5"/></joint>')
        parent = f"l{i}"
    parts.append(f'<link name="tip"/><joint name="tipj" type="fixed"><parent link="{parent}"/>'
                 '<child link="tip"/><origin xyz="0.1 0 0"/></joint></robot>')
    return "\n".join(parts)


def _compare(robot: Robot, seed: int, n: int = 20) -> float:
    rng = np.random.default_rng(seed)
    Q = robot.random_configurations(n, rng)
    V = rng.normal(size=Q.shape) * 2.0
    A = rng.normal(size=Q.shape) * 5.0
    tau = BatchDynamics(robot).inverse_dynamics(Q, V, A)
    ref = np.array([robot.inverse_dynamics(q, v, a) for q, v, a in zip(Q, V, A)])
    return float(np.max(np.abs(tau - ref)) / max(1.0, np.max(np.abs(ref))))


@pytest.mark.parametrize("backend", ["core", "numba"])
@pytest.mark.parametrize("name", ["panda", "planar2r", "planar5", "seed000_6dof"])
def test_bundled_robots_match_drake(monkeypatch, name, backend):
    if backend == "numba":
        monkeypatch.setenv(ENVIRONMENT, "0")  # the numba kernel, the fallback where the core is not built
    elif compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
    assert _compare(drake_mh.load_robot(name), 0) < 1e-12


def test_shapes_that_differ_are_refused():
    dynamics = BatchDynamics(drake_mh.load_robot("planar2r"))
    with pytest.raises(InvalidArgument, match="one shape"):
        dynamics.inverse_dynamics(np.zeros((3, 2)), np.zeros((2, 2)), np.zeros((3, 2)))


@settings(max_examples=10, deadline=None)
@given(n=st.integers(1, 6), seed=st.integers(0, 10_000), prismatic_every=st.sampled_from([0, 2, 3]))
def test_random_chains_match_drake(n, seed, prismatic_every):
    robot = Robot(_random_urdf(n, seed, prismatic_every), ee_frame="tip")
    assert _compare(robot, seed) < 1e-11


def test_gravity_flag_and_path_coefficients():
    robot = drake_mh.load_robot("panda")
    dyn = BatchDynamics(robot)
    rng = np.random.default_rng(3)
    P = robot.random_configurations(5, rng)
    Ps, Pss = rng.normal(size=P.shape), rng.normal(size=P.shape)
    g = np.array([robot.gravity_torques(q) for q in P])
    zeros = np.zeros_like(P)
    assert np.allclose(dyn.inverse_dynamics(P, zeros, zeros), g, atol=1e-12)
    assert np.allclose(dyn.inverse_dynamics(P, zeros, zeros, gravity=False), 0.0, atol=1e-12)
    a, b, c = dyn.path_coefficients(P, Ps, Pss)
    # tau(q = p, qd = p' sd, qdd = p' sdd + p'' sd^2) = a sdd + b sd^2 + c for any sd, sdd
    sd, sdd = 0.7, -1.3
    ref = np.array([robot.inverse_dynamics(p, ps * sd, ps * sdd + pss * sd ** 2)
                    for p, ps, pss in zip(P, Ps, Pss)])
    assert np.allclose(a * sdd + b * sd ** 2 + c, ref, atol=1e-10)


@pytest.mark.parametrize("backend", ["core", "numba"])
def test_angles_of_many_turns_and_odd_batches(monkeypatch, backend):
    """Continuous joints can sit many turns from zero: the torques at ``q + 2πk`` (k up to 1e8,
    and one beyond the vectorized sine's range) are Drake's at the same ``q``; a batch of any
    length gives each sample the torques it gets alone."""
    if backend == "numba":
        monkeypatch.setenv(ENVIRONMENT, "0")
    elif compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
    robot = drake_mh.load_robot("panda")
    rng = np.random.default_rng(3)
    Q = robot.random_configurations(7, rng) + 2.0 * np.pi * np.array([0, 1, -3, 1e3, -1e5, 1e8, 1e10])[:, None]
    V, A = rng.normal(size=Q.shape), rng.normal(size=Q.shape) * 4.0
    tau = BatchDynamics(robot).inverse_dynamics(Q, V, A)
    ref = np.array([robot.inverse_dynamics(q, v, a) for q, v, a in zip(Q, V, A)])
    np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-9 * np.max(np.abs(ref)))
    alone = np.vstack([BatchDynamics(robot).inverse_dynamics(Q[i], V[i], A[i]) for i in range(len(Q))])
    np.testing.assert_allclose(alone, tau, rtol=1e-14, atol=1e-14 * np.max(np.abs(tau)))
