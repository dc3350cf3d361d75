"""Honest success flags: verification with Drake, never the optimizer's own fitness."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh
from drake_mh.ik import IKProblem, solve_ik, verify


def _rotated(X, angle):
    """``X`` with its rotation turned by ``angle`` [rad] about world z (same position)."""
    c, s = np.cos(angle), np.sin(angle)
    Y = X.copy()
    Y[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ X[:3, :3]
    return Y


def test_position_reached_orientation_missed_is_failure(panda):
    q = panda.random_configurations(1, 7)[0]
    target = _rotated(panda.fk(q), 0.2)
    problem = IKProblem(panda, target, position_tolerance=1e-5, orientation_tolerance=1e-5)
    result = verify(problem, q, method="test", start=0.0, nfe=0)
    assert result.position_error < 1e-12
    assert result.orientation_error == pytest.approx(0.2, abs=1e-9)
    assert result.success is False
    assert "orientation error" in result.message


def test_solver_blind_to_orientation_is_not_reported_successful(panda):
    """With orientation_weight = 0 the optimizers' fitness ignores the orientation: they reach the
    position, but verification against the pose tolerances says no."""
    q = panda.random_configurations(1, 8)[0]
    target = _rotated(panda.fk(q), 0.5)
    problem = IKProblem(panda, target, position_tolerance=1e-3, orientation_tolerance=1e-3, orientation_weight=0.0)
    for method, budget in (("de", 3000), ("hybrid", 3000)):
        result = solve_ik(problem, method, seed=0, budget=budget)
        assert not result.success, method
        e_p, e_o = problem.pose_errors(result.q[None])
        assert result.position_error == pytest.approx(e_p[0], abs=1e-12)
        assert result.orientation_error == pytest.approx(e_o[0], abs=1e-9)
        assert result.orientation_error > 1e-3
    # the hybrid does reach the position (its LM drives the translational rows to zero)
    assert result.position_error < 1e-3


def test_outside_limits_is_failure(panda):
    q = panda.home.copy()
    q[3] = panda.upper[3] + 1e-6  # joint 4 just above its upper limit
    problem = IKProblem(panda, panda.fk(q))
    result = verify(problem, q, method="test", start=0.0, nfe=0)
    assert result.position_error < 1e-12 and not result.within_limits and not result.success
    assert "panda_joint4" in result.message


def test_result_fields_and_json(panda):
    problem = IKProblem(panda, panda.fk(panda.home)[:3, 3])
    result = solve_ik(problem, "hybrid", seed=0, budget=5000)
    data = result.to_dict()
    for key in ("q", "success", "position_error", "orientation_error", "min_distance", "within_limits",
                "time", "nfe", "method", "message"):
        assert key in data
    assert result.success and data["min_distance"] is None and len(data["q"]) == 7
    assert 0 < result.nfe <= 5000 and result.time > 0


@pytest.mark.parametrize("method", ["hybrid", "pso", "dls", "drake_snopt"])
def test_unreachable_target_spends_no_budget(panda, method):
    problem = IKProblem(panda, [1.5, 0.0, 0.5])
    result = solve_ik(problem, method, seed=0, budget=10_000)
    assert not result.success and result.nfe == 0 and result.attempts == 0
    assert "out of reach" in result.message
    distance = np.linalg.norm(problem.p_WT - problem.reach.p_WO)
    assert f"{distance:.4f} m" in result.message and f"{problem.reach.radius:.4f} m" in result.message


def test_just_inside_the_bound_is_attempted(six_dof):
    """The bound is not used to refuse reachable targets: the stretched arm is inside it."""
    problem = IKProblem(six_dof, [0.0, 0.0, 0.5])
    assert problem.unreachable_reason() is None
    far = IKProblem(six_dof, problem.reach.p_WO + [problem.reach.radius + 0.01, 0, 0])
    assert far.unreachable_reason() is not None


def test_top_level_names():
    assert drake_mh.solve_ik is solve_ik and drake_mh.IKProblem is IKProblem
    assert drake_mh.IKResult.__name__ == "IKResult"
