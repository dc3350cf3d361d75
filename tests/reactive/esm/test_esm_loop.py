"""ESM closed loop on the paper's scenarios: safety, convergence, determinism, reference optimum."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh
from drake_mh.reactive import AMNN, ESMConfig, QPBaseline, get_scenario, optimal_manipulability, run_esm
from drake_mh.reactive.esm.scenarios import TARGET, THETA0, MovingObstacle
from drake_mh.geometry.shapes import Sphere

MU_STAR = 0.16089694     # multi-start SLSQP, flange pinned at the paper's target (docs/esm.md)


@pytest.fixture(scope="module")
def robot():
    return drake_mh.load_robot("panda")


def _assert_verified(run):
    assert np.all(run.joint_violation <= 1e-9)
    assert np.all(run.velocity_violation <= 1e-7)
    assert np.all(run.inequality_violation <= 1e-6)
    assert np.all(run.jacobian_error <= 1e-9)
    assert run.solver_feasible.all()


@pytest.fixture(scope="module")
def scenario_1_amnn(robot):
    """Scenario 1 (Fig. 4) with the default solver, h1 = 10 (docs/esm.md: h1 = 1 leaves the target)."""
    return run_esm(robot, get_scenario("self_motion", config=ESMConfig(h1=10.0)), AMNN(), seed=0)


@pytest.mark.slow
def test_scenario_1_default_solver_is_safe(robot, scenario_1_amnn):
    """The recorded clearances are the true ones, in closed form (the ball against the capsules
    of a fresh Drake plant at each step's configuration and instant), and never below the
    threshold."""
    from references import FreshDrake

    run = scenario_1_amnn
    _assert_verified(run)
    assert run.threshold_violations == 0
    drake = FreshDrake(robot)
    obstacles = get_scenario("self_motion", config=ESMConfig(h1=10.0)).obstacles
    assert all(isinstance(o.shape, Sphere) for o in obstacles)
    closed_form = [min(drake.ball_distance(theta, o.state(t)[0], o.shape.radius) for o in obstacles)
                   for t, theta in zip(run.t, run.theta)]
    np.testing.assert_allclose(run.min_distance, closed_form, atol=1e-9)
    assert min(closed_form) >= run.threshold
    assert run.active_rows.max() >= 1                   # the obstacle did constrain the motion


@pytest.mark.slow
def test_scenario_1_converges(scenario_1_amnn):
    run = scenario_1_amnn
    free = np.concatenate([[True], run.active_rows == 0])
    before = (run.t >= 0.5) & (run.t <= 1.0) & free     # settled, before the sphere arrives
    # the last samples of the convergence reach 1e-5-1e-4 m depending on the random stream
    # (measured 9.9e-6 and 2.4e-5 at t = 0.5 s); then the error drops to the 1e-10 m level
    assert np.max(run.error[before]) < 1e-4 and np.median(run.error[before]) < 1e-6
    assert np.min(run.mu[before]) > 0.95 * MU_STAR
    assert run.error[-1] < 1e-5                         # back on the target after avoiding


@pytest.mark.slow
def test_qp_baseline_scenario_1(robot):
    run = run_esm(robot, get_scenario("self_motion", config=ESMConfig(h1=10.0)), QPBaseline(), seed=0)
    _assert_verified(run)
    assert run.threshold_violations == 0
    assert run.error[-1] < 1e-5
    assert run.mu[36] > 0.95 * MU_STAR


def test_tracking_converges_to_a_moving_target(robot):
    scenario = get_scenario("tracking", config=ESMConfig(h1=100.0), duration=1.5)
    run = run_esm(robot, scenario, AMNN(layers=100, agents=32), seed=1)
    _assert_verified(run)
    assert np.median(run.error[run.t > 0.5]) < 5e-4


def test_paper_weights_leave_the_target(robot):
    """h1 = h2 = 1: the ESM optimum is 3.8 cm off the target (||∇_r 1/μ*|| = 2.39 > h1); AMNN finds it."""
    scenario = get_scenario("self_motion", config=ESMConfig(h1=1.0), duration=1.0)
    run = run_esm(robot, scenario, AMNN(), seed=0, verify=False)
    assert run.error[-1] == pytest.approx(0.0376, abs=2e-3)
    assert run.mu[-1] > MU_STAR


@pytest.mark.parametrize("make", [lambda: AMNN(layers=20, agents=8),
                                  lambda: __import__("drake_mh.reactive", fromlist=["x"]).MetaheuristicSolver(
                                      "pso", budget=200, pop_size=10)], ids=["amnn", "pso"])
def test_warm_start_is_deterministic_per_seed(robot, make):
    scenario = get_scenario("self_motion", config=ESMConfig(h1=10.0))
    a = run_esm(robot, scenario, make(), seed=5, steps=8, verify=False)
    b = run_esm(robot, scenario, make(), seed=5, steps=8, verify=False)
    c = run_esm(robot, scenario, make(), seed=6, steps=8, verify=False)
    np.testing.assert_array_equal(a.theta, b.theta)
    assert not np.array_equal(a.theta, c.theta)
    solver = make()                                        # reset() restarts the same run
    first = run_esm(robot, scenario, solver, seed=5, steps=8, verify=False)
    again = run_esm(robot, scenario, solver, seed=5, steps=8, verify=False)
    np.testing.assert_array_equal(first.theta, again.theta)


def test_moving_obstacle_piecewise_velocity():
    ob = MovingObstacle("o", Sphere(0.1), (0, 0, 0), ((0.0, (0, 1, 0)), (5.0, (0, -1, 0))))
    np.testing.assert_allclose(ob.state(2.0)[0], [0, 2, 0])
    np.testing.assert_allclose(ob.state(7.0)[0], [0, 3, 0])
    np.testing.assert_allclose(ob.state(7.0)[1], [0, -1, 0])


@pytest.mark.slow
def test_reference_optimum(robot):
    mu, theta = optimal_manipulability(robot, TARGET, starts=12, theta_hint=THETA0)
    assert mu == pytest.approx(MU_STAR, rel=1e-6)
    np.testing.assert_allclose(robot.fk(theta)[:3, 3], TARGET, atol=1e-8)
    assert robot.within_limits(theta)


def test_executed_motion_is_certified_between_the_samples(robot):
    """The whole executed motion (not its samples) is certified; Drake's exact distance at 50
    configurations per step, the cube where it is at that instant, never finds a collision; the
    cube's reversal at t = 5 s falls inside a step and is cut there."""
    from drake_mh.reactive.esm.controller import certify_esm_motion
    from drake_mh.scene import Scene

    scenario = get_scenario("tracking", duration=6.0)
    run = run_esm(robot, scenario, QPBaseline(), seed=0)
    assert run.motion_certified and run.motion_first_failure == -1
    assert 0 <= run.motion_min_clearance <= run.min_distance.min()
    cube = scenario.obstacles[0]
    scene = Scene(robot)
    scene.add(cube.name, cube.shape, cube.state(0.0)[0])
    worst = np.inf
    for k in range(150, 200):   # around the reversal (5 s = step 178.6)
        for s in np.linspace(0.0, 1.0, 50):
            scene.move(cube.name, position=cube.state(run.t[k - 1] + s * (run.t[k] - run.t[k - 1]))[0])
            worst = min(worst, scene.min_distance(run.theta[k - 1] + s * (run.theta[k] - run.theta[k - 1])))
    assert worst >= run.motion_min_clearance
    # a ball that crosses the hand's place at step 10 at 1 m/s: the samples (every 28 mm of its
    # travel) may miss it, the certificate refuses the motion and names a step
    import dataclasses

    p_hand = robot.fk(run.theta[10])[:3, 3]
    v = np.array([1.0, 0.0, 0.0])
    ball = MovingObstacle("ball", Sphere(0.01), tuple(p_hand - v * 0.5 * (run.t[9] + run.t[10])),
                          ((0.0, tuple(v)),))
    bad = certify_esm_motion(robot, dataclasses.replace(scenario, obstacles=(ball,)), run.t, run.theta)
    assert not bad["motion_certified"] and 1 <= bad["motion_first_failure"] <= 10


def test_bad_seed_or_starts_of_the_reference_optimum_are_named(robot):
    from drake_mh.errors import InvalidArgument

    for kwargs in ({"seed": 1.5}, {"seed": "abc"}, {"starts": 2.5}, {"starts": -1}):  # 1.5 was truncated
        with pytest.raises(InvalidArgument, match=f"{next(iter(kwargs))} must be an integer >= 0"):
            optimal_manipulability(robot, TARGET, **kwargs)
