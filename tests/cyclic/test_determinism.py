"""Same seed => same result through the cyclic problem (vectorized objective)."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.cases import TABLE_IV, circle_task, maple_leaf_task
from drake_mh.cyclic.planner import component_problem, plan
from drake_mh.optim import minimize


@pytest.fixture(scope="module")
def problem():
    return component_problem(maple_leaf_task(), 0, [])


@pytest.mark.parametrize("method", ["ga", "woa", "pso", "de", "abc"])
def test_same_seed_same_result(problem, method):
    box = [(-0.5, 1.0)]
    a = minimize(problem.objective, box, method=method, budget=300, seed=7, pop_size=20)
    b = minimize(problem.objective, box, method=method, budget=300, seed=7, pop_size=20)
    assert a.x.tobytes() == b.x.tobytes() and np.array_equal(a.history, b.history)
    assert a.nfe == 300 and abs(a.x[0] - TABLE_IV[1]["woa"][1]) < 0.05


def test_objective_is_vectorized(problem):
    X = np.linspace(-0.5, 1.0, 7)[:, None]
    batch = problem.objective(X)
    single = np.array([problem.objective(x[None])[0] for x in X])
    assert np.array_equal(batch, single)


def test_plan_determinism():
    a = plan(circle_task(), method="ga", budget=200, seed=3, converged_n=0)
    b = plan(circle_task(), method="ga", budget=200, seed=3, converged_n=0)
    assert a.ks == b.ks and np.array_equal(a.components[0].result.history, b.components[0].result.history)
