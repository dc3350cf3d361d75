"""Cyclic plans and the pseudoinverse baseline print in a few lines, not their arrays."""

from __future__ import annotations

from drake_mh.cyclic.cases import TABLE_IV, maple_leaf_task
from drake_mh.cyclic.pinv import pinv_tracking
from drake_mh.cyclic.planner import plan, plan_with_k

WOA_K = [TABLE_IV[i]["woa"][1] for i in (1, 2, 3, 4)]


def test_plan_repr_names_task_ks_and_components(planar12):
    task = maple_leaf_task(planar12)
    searched = plan(task, method="pso", budget=60, seed=0)
    text = repr(searched)
    assert len(text.splitlines()) == 3 + len(searched.components) and len(text) < 1500
    assert str(searched) == text
    assert task.name in text and f"fitness (eq. (1), sum) = {searched.fitness:.6g}" in text
    assert "pso: nfe 60" in text and "history" not in text
    given = plan_with_k(task, WOA_K, converged_n=0)
    assert repr(given).count("k given") == 4


def test_pinv_result_repr_gives_sizes_and_worst_figures(planar12):
    leaf = plan_with_k(maple_leaf_task(planar12), WOA_K, converged_n=0)
    result = pinv_tracking(planar12, leaf.task.path, leaf.q([0.0])[0], cycles=2, steps_per_cycle=100)
    text = repr(result)
    assert len(text.splitlines()) == 2 and "1 start(s), 2 cycle(s)" in text
    assert f"closure max {result.closure.max():.3g} rad" in text
