"""Retiming robots as shipped: velocity and torque where no acceleration is declared, derived and
default limits, MoveIt's scaling factors; every check against a fresh Drake plant."""

from __future__ import annotations

import logging

import numpy as np
import pytest
from references import FreshPlant
from robot_fixtures import erd_root
from traj_helpers import random_waypoints

import drake_mh
from drake_mh.errors import InvalidArgument, MissingLimits
from drake_mh.trajectories import certify, retime
from drake_mh.trajectories.limits_for import DEFAULT_ACCELERATION, DEFAULT_JERK, DEFAULT_VELOCITY, DERIVED_MARGIN


@pytest.fixture(scope="module")
def shipped():
    """example-robot-data's UR5 and Panda with hand as shipped (no acceleration limits)."""
    from drake_mh.robot.examples import EXAMPLE_ARMS

    root = erd_root()
    return {name: drake_mh.load_robot(root / EXAMPLE_ARMS[name][0], ee_frame=EXAMPLE_ARMS[name][1])
            for name in ("ur5", "panda_hand")}


def _dense(traj, n=3001):
    t = np.linspace(traj.start_time, traj.end_time, n)
    return t, traj.derivatives(t, 2)


@pytest.mark.parametrize("name", ["ur5", "panda_hand"])
@pytest.mark.parametrize("seed", [0, 1])
def test_default_retiming_of_a_shipped_urdf_keeps_velocity_and_torque(shipped, name, seed):
    """No acceleration limit anywhere: toppra times the path under velocity and torque (gravity
    included); Drake's own inverse dynamics on a fresh plant finds every sample within limits."""
    robot = shipped[name]
    assert not np.any(np.isfinite(robot.acceleration_limits))
    W = random_waypoints(robot, np.random.default_rng(seed), k=4, spread=0.5)
    traj = retime(W, robot)
    table = traj.info["enforced_limits"]
    assert table.enforced == ("velocity", "effort") and traj.info["limits"] == ("velocity", "torque")
    assert set(table.sources("velocity")) == {"declared"} and set(table.sources("effort")) == {"declared"}
    assert set(table.details("acceleration")) == {"bounded through the torque limits"}
    _, (Q, V, A) = _dense(traj)
    reference = FreshPlant(robot)
    tau = reference.torques(Q, V, A)
    assert np.all(np.abs(V) <= robot.velocity_limits * (1 + 1e-6))
    assert np.all(np.abs(tau) <= robot.effort_limits * (1 + 1e-6))
    assert np.max(np.abs(tau) / robot.effort_limits) > 0.5  # torque binds somewhere: it is what bounds the motion
    # the certificate's acceleration bound holds at every dense sample, with no declared limit
    assert np.all(np.abs(A) <= traj.info["certificate"].bounds["acceleration"] * (1 + 1e-9))


def test_ruckig_derives_accelerations_that_keep_torque_within_effort(shipped):
    """The derived bounds satisfy their rule against Drake's mass matrix and gravity on a fresh
    plant, and the ruckig trajectory's torques (Drake) stay within the effort limits."""
    robot = shipped["ur5"]
    W = random_waypoints(robot, np.random.default_rng(3), k=3, spread=0.5)
    traj = retime(W, robot, "ruckig")
    table = traj.info["enforced_limits"]
    assert set(table.sources("acceleration")) == {"derived"} and set(table.sources("jerk")) == {"default"}
    assert np.all(table["jerk"] == DEFAULT_JERK)
    a = table["acceleration"]
    reference = FreshPlant(robot)
    u = np.linspace(0.0, 1.0, 32)[:, None]
    for q in np.concatenate([W[k] + u * (W[k + 1] - W[k]) for k in range(len(W) - 1)]):
        load = np.abs(reference.mass_matrix(q)) @ a + np.abs(reference.gravity(q))
        assert np.all(load <= robot.effort_limits * (1 + 1e-9))
    _, (Q, V, A) = _dense(traj)
    assert np.all(np.abs(reference.torques(Q, V, A)) <= robot.effort_limits * (1 + 1e-6))
    assert np.all(np.abs(A) <= a * (1 + 1e-6))
    # the rule's margin is used up on some joint at some sample (the bound is not needlessly low)
    loads = [np.max((np.abs(reference.mass_matrix(q)) @ (a / DERIVED_MARGIN) + np.abs(reference.gravity(q)))
                    / robot.effort_limits) for q in W]
    assert max(loads) > 0.5


def test_where_nothing_bounds_a_joint_documented_defaults_apply_with_a_warning(caplog):
    robot = drake_mh.load_robot("planar2r")
    robot.effort_limits = [np.inf, np.inf]
    robot.acceleration_limits = [np.inf, np.inf]
    robot.velocity_limits = [np.inf, 1.0]
    W = random_waypoints(robot, np.random.default_rng(0), k=3)
    with caplog.at_level(logging.WARNING, logger="drake_mh"):
        traj = retime(W, robot)
    table = traj.info["enforced_limits"]
    assert table.sources("velocity") == ("default", "user") and table["velocity"][0] == DEFAULT_VELOCITY
    assert table.sources("acceleration") == ("default", "default") and np.all(table["acceleration"] == DEFAULT_ACCELERATION)
    warned = " ".join(r.getMessage() for r in caplog.records)
    assert "no velocity limit declared on joints ['joint1']" in warned and "10 rad/s²" in warned
    _, (Q, V, A) = _dense(traj)
    assert np.all(np.abs(A) <= DEFAULT_ACCELERATION * (1 + 1e-6)) and np.all(np.abs(V[:, 0]) <= DEFAULT_VELOCITY * (1 + 1e-6))
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="drake_mh"):
        retime(W, robot)
    assert not caplog.records  # once per robot


def test_scaling_factors_scale_the_limits_as_moveit_does(panda, shipped):
    W = random_waypoints(panda, np.random.default_rng(2), k=3)
    full = retime(W, panda)
    slow = retime(W, panda, velocity_scaling=0.5, acceleration_scaling=0.25)
    table = slow.info["enforced_limits"]
    assert np.allclose(table["velocity"], 0.5 * panda.velocity_limits)
    assert np.allclose(table["acceleration"], 0.25 * panda.acceleration_limits)
    assert table.scaling == {"velocity": 0.5, "acceleration": 0.25} and slow.duration > full.duration
    _, (Q, V, A) = _dense(slow)
    assert np.all(np.abs(V) <= 0.5 * panda.velocity_limits * (1 + 1e-6))
    assert np.all(np.abs(A) <= 0.25 * panda.acceleration_limits * (1 + 1e-6))
    # torque-bounded robot: scaling the acceleration enforces a scaled derived bound
    robot = shipped["ur5"]
    W = random_waypoints(robot, np.random.default_rng(2), k=3, spread=0.5)
    scaled = retime(W, robot, acceleration_scaling=0.5)
    table = scaled.info["enforced_limits"]
    assert "acceleration" in table.enforced and set(table.sources("acceleration")) == {"derived"}
    _, (Q, V, A) = _dense(scaled)
    assert np.all(np.abs(A) <= table["acceleration"] * (1 + 1e-6))
    for bad in (0.0, 1.5, -1, float("nan"), "fast", True):
        with pytest.raises(InvalidArgument, match="velocity_scaling must be a number in"):
            retime(W, robot, velocity_scaling=bad)


def test_torque_asked_of_a_robot_without_effort_limits_says_how(panda):
    robot = drake_mh.load_robot("planar2r")
    robot.effort_limits = [np.inf, np.inf]
    W = random_waypoints(robot, np.random.default_rng(0), k=2)
    with pytest.raises(MissingLimits) as err:
        retime(W, robot, limits=("velocity", "torque"))
    text = str(err.value)
    assert "effort" in text and "limits=PATH" in text and len(text) < 400 and "load_problem_robot" not in text


def test_recertifying_checks_what_the_maker_enforced(panda):
    """``certify(traj, robot).check()`` on a toppra trajectory of a robot with jerk limits: toppra
    does not limit jerk (its acceleration steps), and re-certifying says so instead of failing."""
    W = np.array([panda.home, panda.home + 0.4, panda.home - 0.3])
    traj = drake_mh.retime(W, panda, method="toppra")
    cert = drake_mh.certify(traj, panda)
    cert.check()
    assert cert.enforced == traj.info["certificate"].enforced and "jerk (not enforced)" in cert.table()
    assert not certify(traj, panda, enforced=("jerk",)).ok()  # asked for, the jerk is still checked
