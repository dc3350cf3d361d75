"""ESM control step: constraints (eqs. (6)-(9), (11)), objective, repair, and every solver's
answer checked with Drake, independently of the solver."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh
from drake_mh.errors import InvalidArgument, InvalidConfiguration, UnknownMethod
from drake_mh.reactive import (
    AMNN,
    ESMConfig,
    ESMObjective,
    MetaheuristicSolver,
    QPBaseline,
    build_step,
    check_step,
    drake_point_jacobian,
    point_jacobian,
)
from drake_mh.reactive.esm.scenarios import THETA0, TARGET
from drake_mh.scene import Box, Scene, Sphere


@pytest.fixture(scope="module")
def robot():
    return drake_mh.load_robot("panda")


def _scene(robot, position=(0.0, -0.16, 0.6), velocity=(0.0, 0.16, 0.0), shape=None):
    scene = Scene(robot)
    scene.add("ball", shape or Sphere(0.15), position, velocity=velocity)
    return scene


@pytest.fixture(scope="module")
def close_step(robot):
    """A step with the sphere close to the upper arm and approaching: obstacle rows active."""
    return build_step(robot, _scene(robot), np.array(THETA0), TARGET, ESMConfig(h1=10.0))


def test_box_is_eq_11(robot, close_step):
    theta = np.array(THETA0)
    step_max = robot.velocity_limits * close_step.config.dt
    np.testing.assert_allclose(close_step.lower, np.maximum(robot.lower, theta - step_max))
    np.testing.assert_allclose(close_step.upper, np.minimum(robot.upper, theta + step_max))


def test_box_at_a_joint_limit(robot):
    theta = np.array(THETA0)
    theta[3] = robot.upper[3]                        # joint 4 exactly on its upper limit
    step = build_step(robot, _scene(robot, position=(2, 2, 2)), theta, TARGET)
    assert step.upper[3] <= robot.upper[3] + 1e-12 and step.lower[3] < step.upper[3]


def test_rows_from_drake_pairs(robot, close_step):
    pairs = [p for p in _scene(robot).distances(np.array(THETA0)) if not p.is_self]
    assert len(close_step.rows) + len(close_step.fixed_rows) == len(pairs)
    assert "panda_link0" in {r.link for r in close_step.fixed_rows}      # the base cannot move away
    assert not close_step.relaxed_rows
    row = min(close_step.rows, key=lambda r: r.distance)
    D = row.distance - close_step.config.threshold - close_step.config.buffer
    assert row.V == pytest.approx((1 / (1 + np.exp(-abs(D))) - 0.5) * np.sign(D))
    assert row.V0 == pytest.approx(row.u_W @ np.array([0.0, 0.16, 0.0]))
    np.testing.assert_allclose(np.linalg.norm(row.u_W), 1.0)


def test_point_jacobian_eq_8_matches_drake(robot):
    rng = np.random.default_rng(3)
    for q in robot.random_configurations(5, rng):
        for link in ("panda_link2", "panda_link4", "panda_link7"):
            p_WM = robot.fk(q, link)[:3, 3] + rng.normal(scale=0.05, size=3)
            np.testing.assert_allclose(point_jacobian(robot, q, link, p_WM),
                                       drake_point_jacobian(robot, q, link, p_WM), atol=1e-12)
    assert not point_jacobian(robot, THETA0, "panda_link0", [0, 0, 0.1]).any()


def test_objective_matches_drake(robot, close_step):
    """The error and μ (eq. (3): sqrt(det(J_v J_vᵀ))) from Drake on a fresh plant, by hand."""
    from references import FreshDrake

    drake = FreshDrake(robot)
    Q = np.clip(np.array(THETA0) + np.random.default_rng(0).normal(scale=0.03, size=(6, 7)),
                close_step.lower, close_step.upper)
    F, e, mu = ESMObjective(robot, close_step).values(Q)
    for q, Fi, ei, mi in zip(Q, F, e, mu):
        e_drake = np.linalg.norm(drake.fk(q, robot.ee_frame_name)[:3, 3] - np.array(TARGET))
        Jv = drake.jacobian(q, robot.ee_frame_name)[3:]
        mu_drake = np.sqrt(np.linalg.det(Jv @ Jv.T))
        assert ei == pytest.approx(e_drake, abs=1e-12)
        assert mi == pytest.approx(mu_drake, rel=1e-10)
        assert Fi == pytest.approx(10.0 * e_drake + 1.0 / mu_drake, rel=1e-10)


def test_reject_gives_inf_and_repair_restores_feasibility(robot, close_step):
    rng = np.random.default_rng(1)
    X = close_step.lower + rng.random((200, 7)) * (close_step.upper - close_step.lower)
    ok = close_step.feasible(X)
    assert ok.any() and not ok.all()
    F = ESMObjective(robot, close_step, "reject")(X)
    assert np.all(np.isinf(F[~ok])) and np.all(np.isfinite(F[ok]))
    Xr, ok_r = close_step.repair(X)
    assert ok_r.all() and close_step.feasible(Xr).all()
    assert np.all(close_step.violation(Xr) <= 1e-8)
    np.testing.assert_array_equal(Xr[ok], X[ok])               # feasible rows untouched
    F_rep = ESMObjective(robot, close_step, "repair")(X)
    np.testing.assert_allclose(F_rep, ESMObjective(robot, close_step).values(Xr)[0])


@pytest.mark.parametrize("make", [
    lambda: AMNN(layers=30, agents=16),
    lambda: AMNN(layers=30, agents=16, handling="repair"),
    lambda: MetaheuristicSolver("pso", budget=500, pop_size=20),
    lambda: MetaheuristicSolver("de", budget=500, pop_size=20),
    lambda: QPBaseline(),
], ids=["amnn", "amnn-repair", "pso", "de", "qp"])
@pytest.mark.parametrize("where", ["sphere", "box"])
def test_solver_step_respects_limits_and_inequality(robot, make, where):
    """Every solver's answer satisfies eq. (11) and eq. (9), checked with Drake's Jacobians."""
    shape = Sphere(0.15) if where == "sphere" else Box((0.12, 0.12, 0.12))
    position = (0.0, -0.16, 0.6) if where == "sphere" else (0.25, -0.12, 0.62)
    scene = _scene(robot, position, shape=shape)
    solver = make()
    solver.reset(0)
    theta = np.array(THETA0)
    for _ in range(3):                                   # warm-started steps
        step = build_step(robot, scene, theta, TARGET, ESMConfig(h1=10.0))
        assert any(r.rhs < 0.5 for r in step.rows)       # the inequality matters here
        sol = solver.solve(robot, step)
        check = check_step(robot, step, sol.theta)
        assert sol.feasible
        assert check.ok(), check
        assert np.all(sol.theta >= step.lower - 1e-12) and np.all(sol.theta <= step.upper + 1e-12)
        theta = sol.theta


def test_answer_never_worse_than_standing_still(robot, close_step):
    theta_prev_F = ESMObjective(robot, close_step).values(close_step.repair(close_step.theta_prev[None])[0])[0][0]
    solver = AMNN(layers=10, agents=8)
    solver.reset(0)
    assert solver.solve(robot, close_step).F <= theta_prev_F


def test_config_and_solver_errors(robot):
    with pytest.raises(InvalidArgument, match="step_fraction"):
        ESMConfig(step_fraction=2.0)
    with pytest.raises(InvalidArgument, match="dt"):
        ESMConfig(dt=0.0)
    with pytest.raises(InvalidArgument, match="layers"):
        AMNN(layers=0)
    for seed in ("abc", -1, 1.5):  # numpy's TypeError / ValueError before
        with pytest.raises(InvalidArgument, match="seed must be"):
            AMNN(layers=2, agents=4).reset(seed)
    with pytest.raises(UnknownMethod, match="pso"):
        MetaheuristicSolver("nope", budget=10)
    with pytest.raises(InvalidArgument, match="handling"):
        MetaheuristicSolver("pso", budget=10, handling="penalty")
    with pytest.raises(InvalidArgument, match="unknown parameter"):
        MetaheuristicSolver("pso", budget=10, nope=1)
    theta = np.array(THETA0)
    theta[3] = 0.5                                       # joint 4 must be negative on a Panda
    with pytest.raises(InvalidConfiguration, match="joint limits"):
        build_step(robot, _scene(robot), theta, TARGET)
