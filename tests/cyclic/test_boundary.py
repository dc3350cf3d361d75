"""Feasible intervals of k: inside => within limits and collision-free, outside => not."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.cases import TABLE_IV, maple_leaf_task
from drake_mh.cyclic.obstacles import CircleObstacle
from drake_mh.cyclic.planner import component_problem

WOA_K = [TABLE_IV[i]["woa"][1] for i in (1, 2, 3, 4)]


@pytest.fixture(scope="module")
def leaf_problems():
    task = maple_leaf_task()
    return [component_problem(task, i, WOA_K[:i]) for i in range(4)]


@pytest.mark.parametrize("index", [0, 1, 2, 3])
def test_inside_feasible_outside_not(leaf_problems, index):
    problem = leaf_problems[index]
    intervals = problem.feasible_intervals()
    assert intervals, "every leaf component has feasible k"
    rng = np.random.default_rng(index)
    for lo, hi in intervals:
        k = np.concatenate([[lo, hi], rng.uniform(lo, hi, 64)])
        ev = problem.evaluate(k)
        assert ev.feasible.all()
        assert np.all(ev.reachable) and np.all(ev.limit_excess == 0) and np.all(ev.clearance > 0)
        theta = ev.theta
        assert np.all(theta >= problem.lower - 1e-12) and np.all(theta <= problem.upper + 1e-12)
        outside = problem.evaluate([lo - 1e-8, hi + 1e-8, lo - 0.05, hi + 0.05])
        assert not outside.feasible.any()
        # what fails just outside is one of the three constraints
        assert np.all(~outside.reachable | (outside.limit_excess > 0) | (outside.clearance <= 0))


def test_obstacles_shrink_the_interval():
    task = maple_leaf_task()
    free = maple_leaf_task(obstacles=())
    with_obstacles = component_problem(task, 3, WOA_K[:3]).feasible_intervals()
    without = component_problem(free, 3, WOA_K[:3]).feasible_intervals()
    assert without[0][0] < with_obstacles[0][0] - 0.3  # the leaf-side obstacle cuts ~0.35 rad
    # eq. (21) read sensibly: a colliding k is infeasible (+inf), never rewarded with 0
    problem = component_problem(task, 3, WOA_K[:3])
    k_collide = 0.5 * (without[0][0] + with_obstacles[0][0])
    assert problem.evaluate([k_collide]).clearance[0] <= 0
    assert problem.objective(np.array([[k_collide]]))[0] == np.inf


def test_boundary_band_contains_feasible_k(leaf_problems):
    problem = leaf_problems[0]
    b = problem.boundary(n_grid=181)
    (lo, hi), = b.k_intervals
    assert np.all(b.theta_g_min <= lo + 1e-9) and np.all(b.theta_g_max >= hi - 1e-9)
    assert np.all(b.shrunk_min <= lo + 2 * np.diff(b.grid)[0]) and np.all(b.shrunk_max >= hi - 2 * np.diff(b.grid)[0])


def test_negative_root_violates_eq27(leaf_problems):
    """The paper: only the positive root satisfies eq. (27) (0 <= middle joint <= π)."""
    task = maple_leaf_task()
    comps = list(task.components)
    from drake_mh.cyclic.task import CyclicTask, ThreeLinkComponent
    comps[0] = ThreeLinkComponent(comps[0].target, root=-1, name="component 1 (-)")
    neg = CyclicTask(task.lengths, tuple(comps), task.lower, task.upper, task.obstacles)
    assert component_problem(neg, 0, []).feasible_intervals() == []


def test_link_radius_shrinks(leaf_problems):
    task = maple_leaf_task(link_radius=0.025)
    thick = component_problem(task, 3, WOA_K[:3]).feasible_intervals()
    thin = leaf_problems[3].feasible_intervals()
    assert thick[0][0] > thin[0][0]
    assert CircleObstacle((0.0, 0.0), 0.1).radius == 0.1
