"""Composed plans: cyclic to ~1e-12, the end effector on the path (Drake), export, errors."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.cases import TABLE_IV, circle_task, maple_leaf_task
from drake_mh.cyclic.pinv import pinv_tracking
from drake_mh.cyclic.planner import plan, plan_with_k
from drake_mh.cyclic.problem import InfeasibleComponent
from drake_mh.cyclic.task import CyclicTask
from drake_mh.cyclic.verify import cycle_report, verify
from drake_mh.errors import InvalidArgument, UnsupportedModel

WOA_K = [TABLE_IV[i]["woa"][1] for i in (1, 2, 3, 4)]


@pytest.fixture(scope="module")
def leaf_plan(planar12):
    return plan_with_k(maple_leaf_task(planar12), WOA_K, converged_n=1024)


def test_task_from_drake_matches_paper(planar12, planar5):
    assert np.allclose(maple_leaf_task(planar12).lengths, 0.30, atol=1e-12)
    assert np.allclose(maple_leaf_task(planar12).lower, maple_leaf_task().lower)
    assert np.allclose(circle_task(planar5).lengths, [0.22, 0.20, 0.18, 0.16, 0.14], atol=1e-12)


def test_leaf_plan_verified_with_drake(leaf_plan, planar12):
    v = verify(leaf_plan, planar12, cycles=3, samples_per_cycle=500)
    assert v.success, v
    assert v.ee_error < 1e-12 and v.drake_fk_error < 1e-12
    assert v.closure < 1e-12
    assert v.max_step < 0.1  # continuous: no 2π wraps


def test_cyclic_to_machine_precision(leaf_plan):
    report = cycle_report(leaf_plan, cycles=50, samples_per_cycle=20)
    assert report.drift.max() < 1e-12 and report.closure.max() < 1e-12
    assert report.limit_excess.max() == 0.0 and report.tracking_error.max() < 1e-12


def test_export(leaf_plan, tmp_path):
    t, Q = leaf_plan.trajectory(cycles=2, samples_per_cycle=50)
    assert t.shape == (101,) and Q.shape == (101, 12)
    assert np.allclose(Q[0], Q[50], atol=1e-12) and np.allclose(Q[0], Q[-1], atol=1e-12)
    pp = leaf_plan.to_piecewise_polynomial(cycles=1, samples_per_cycle=50)
    assert np.allclose(pp.value(t[7]).ravel(), Q[7], atol=1e-12)
    leaf_plan.save_npz(tmp_path / "leaf.npz")
    data = np.load(tmp_path / "leaf.npz")
    assert data["q"].shape[1] == 12 and np.allclose(data["ks"], WOA_K)


def test_five_dof_plan_both_roots(planar5):
    for root in (1, -1):
        p = plan(circle_task(planar5, root=root), method="woa", budget=200, seed=0, converged_n=0)
        v = verify(p, planar5, cycles=2, samples_per_cycle=400)
        assert v.success, (root, v)


def test_printed_five_dof_case_is_infeasible():
    with pytest.raises(InfeasibleComponent, match=r"0\.311 \.\. 0\.9338 m .* reach is 0 \.\. 0\.48 m"):
        plan(circle_task(knots="paper"), budget=40)


def test_errors(planar12, planar5):
    with pytest.raises(InvalidArgument, match="one k per 3-link"):
        plan_with_k(maple_leaf_task(), [0.1])
    with pytest.raises(InfeasibleComponent, match="infeasible"):
        plan_with_k(maple_leaf_task(), [3.0, 0.3, -1.3, 1.4])
    with pytest.raises(InvalidArgument, match="joints"):
        verify(plan_with_k(circle_task(), [3.0], converged_n=0), planar12)
    with pytest.raises(InvalidArgument, match="cover 12 joints but the arm has 5"):
        CyclicTask.for_robot(planar5, maple_leaf_task().components)
    import drake_mh
    with pytest.raises(UnsupportedModel, match="planar"):
        CyclicTask.for_robot(drake_mh.load_robot("panda"), maple_leaf_task().components)


def test_pinv_baseline_drifts_while_plan_closes(leaf_plan, planar12):
    q0 = leaf_plan.q([0.0])[0]
    result = pinv_tracking(planar12, leaf_plan.task.path, q0, cycles=3, steps_per_cycle=200)
    assert result.tracking_error.max() < 1e-5  # it does track the path ...
    assert result.closure.min() > 1e-3         # ... but does not come back to q0
    assert np.all(np.diff(result.drift[0]) > 0)
    assert result.q.shape[0] == 1 and result.q_start.shape == (1, 4, 12)


def test_a_component_keeps_copies_of_its_lengths_and_limits():
    """ThreeLinkProblem kept views of the caller's arrays; ragged or text ones raised numpy's errors."""
    from drake_mh.cyclic.problem import ThreeLinkProblem

    def base(r):
        return np.zeros((len(r), 2)), np.zeros(len(r))

    def target(r):
        return np.tile([0.5, 0.2], (len(r), 1))

    lengths, lower, upper = np.array([0.3, 0.3, 0.2]), -np.full(3, 3.0), np.full(3, 3.0)
    component = ThreeLinkProblem(lengths, base, target, lower, upper, n_samples=16)
    lengths[0], lower[0] = 9.0, 0.0
    assert component.lengths[0] == 0.3 and component.lower[0] == -3.0
    for bad in ({"lengths": [[0.3], [0.3, 0.2]]}, {"lengths": "abc"}, {"lower": [0, 0, 1j]}, {"n_samples": "16"}):
        arguments = {"lengths": [0.3, 0.3, 0.2], "lower": lower, "upper": upper, "n_samples": 16, **bad}
        with pytest.raises(InvalidArgument, match=next(iter(bad))):
            ThreeLinkProblem(arguments["lengths"], base, target, arguments["lower"], arguments["upper"],
                             n_samples=arguments["n_samples"])


def test_a_bad_seed_is_named_before_any_work(planar5):
    for seed in ("abc", -1, 1.5):  # 1.5 was truncated to 1, the others numpy's errors
        with pytest.raises(InvalidArgument, match="seed must be an integer >= 0"):
            plan(circle_task(planar5), "woa", budget=40, seed=seed)
