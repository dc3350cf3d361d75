"""The fused numba kernel gives the numpy path's numbers (feasible and infeasible k)."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.cases import TABLE_IV, circle_task, maple_leaf_task
from drake_mh.cyclic.planner import component_problem

WOA_K = [TABLE_IV[i]["woa"][1] for i in (1, 2, 3, 4)]


@pytest.mark.parametrize("case", ["leaf0", "leaf3", "circle+", "circle-", "leaf3_thick"])
def test_kernel_equals_numpy(case):
    if case.startswith("leaf"):
        task = maple_leaf_task(link_radius=0.025 if case.endswith("thick") else 0.0)
        i = int(case[4])
        problem = component_problem(task, i, WOA_K[:i])
    else:
        problem = component_problem(circle_task(root=1 if case.endswith("+") else -1), 1, [])
    k = np.concatenate([np.linspace(-np.pi, np.pi, 181), np.random.default_rng(0).uniform(-4, 4, 50)])
    ev = problem.evaluate(k)
    feasible, fitness = problem.evaluate_fast(k)
    assert np.array_equal(feasible, ev.feasible)
    assert np.allclose(fitness, ev.fitness, rtol=1e-12, atol=1e-9)
    assert feasible.any() and not feasible.all()
