"""Drake's InverseKinematics with SNOPT and IPOPT (both ship with the pip wheel)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument
from drake_mh.ik import IKProblem, solve_ik
from drake_mh.ik.drake import DrakeIKConfig


@pytest.mark.parametrize("method", ["drake_snopt", "drake_ipopt"])
def test_position_only(panda, method):
    problem = IKProblem(panda, [0.45, 0.15, 0.5])
    result = solve_ik(problem, method, seed=0, budget=5)
    assert result.success and result.position_error <= 1e-3 and result.within_limits
    assert result.nfe == 0 and 1 <= result.attempts <= 5 and result.method == method


@pytest.mark.parametrize("method, orientation", [("drake_snopt", "constraint"), ("drake_snopt", "cost"),
                                                 ("drake_ipopt", "cost")])
def test_full_pose_at_trac_ik_tolerance(panda, panda_targets, method, orientation):
    problem = IKProblem(panda, panda_targets[0], position_tolerance=1e-5, orientation_tolerance=1e-5)
    result = solve_ik(problem, method, seed=0, budget=10, config=DrakeIKConfig(orientation=orientation))
    assert result.success, result.message
    assert result.position_error <= 1e-5 and result.orientation_error <= 1e-5


def test_attempts_and_timeout(panda):
    problem = IKProblem(panda, [0.3, 0.0, 0.6], position_tolerance=1e-300)  # never verified
    result = solve_ik(problem, "drake_snopt", seed=0, budget=3)
    assert not result.success and result.attempts == 3 and "attempts exhausted" in result.message
    start = time.process_time()  # a bound on the work, not a timing (studies/timeout_overrun.py)
    result = solve_ik(problem, "drake_snopt", seed=0, timeout=0.02)
    assert time.process_time() - start < 40 * 0.02
    assert not result.success and "timeout" in result.message


def test_reference_cost(panda):
    q_ref = panda.random_configurations(1, 4)[0]
    target = panda.fk(q_ref)[:3, 3]
    result = solve_ik(IKProblem(panda, target, q_ref=q_ref, ref_weight=1.0), "drake_snopt", budget=1)
    assert result.success and np.linalg.norm(result.q - q_ref) < 1e-3  # first guess is q_ref


def test_config_errors():
    with pytest.raises(InvalidArgument, match="orientation must be"):
        DrakeIKConfig(orientation="both")
    with pytest.raises(InvalidArgument, match="max_attempts"):
        DrakeIKConfig(max_attempts=0)
