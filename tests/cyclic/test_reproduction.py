"""The paper's Tables II-IV against our implementation (the facts of REFERENCES.md).

Observed (and asserted): at the printed k, Table IV's fitness values reproduce with the
MATLAB-style evaluation of eq. (1) to |Δ| <= 8.2e-7 (7-8 significant digits) for 7 of the 8
entries and 5.4e-6 for component 4's WOA entry (printed 15.255025 at the same k = 1.4053 as
GA's 15.25502: the two cannot both hold at k = 1.4053; the WOA k was presumably not exactly
1.4053). Component 2 reproduces only with moving base II at phase π/3 and component 3 only
with π/6 (printed): the paper's numbers use two different moving bases II.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_mh.cyclic.cases import TABLE_III_SEARCH, TABLE_IV, circle_task, maple_leaf_task, moving_bases
from drake_mh.cyclic.curves import MapleLeaf
from drake_mh.cyclic.planner import component_problem
from drake_mh.cyclic.problem import ThreeLinkProblem

L3 = (0.30, 0.30, 0.30)
LOWER, UPPER = (-math.pi, 0.0, -math.pi), (math.pi, math.pi, math.pi)


def _problem(base_curve, target_curve):
    T = 2 * math.pi

    def base(r):
        if base_curve is None:
            return np.zeros((len(r), 2)), 0.0
        return base_curve.position(np.asarray(r) * T), 0.0
    return ThreeLinkProblem(L3, base, lambda r: target_curve.position(np.asarray(r) * T), LOWER, UPPER)


def _components(phase_target_ii, phase_base_ii):
    b1, _, b3 = moving_bases()
    b2_target = moving_bases(phase_target_ii)[1]
    b2_base = moving_bases(phase_base_ii)[1]
    return {1: (None, b1), 2: (b1, b2_target), 3: (b2_base, b3), 4: (b3, MapleLeaf())}


@pytest.mark.parametrize("component", [1, 2, 3, 4])
def test_table_iv_reproduces_matlab_style(component):
    base, target = _components(math.pi / 3, math.pi / 6)[component]
    problem = _problem(base, target)
    for method in ("ga", "woa"):
        paper_f, k = TABLE_IV[component][method]
        ours = problem.evaluate([k]).fitness[0]
        tol = 6e-6 if (component, method) == (4, "woa") else 8.2e-7
        assert abs(ours - paper_f) <= tol, (component, method, ours, paper_f)


def test_the_two_moving_bases_ii():
    """Printed phase π/6 for component 2 (as a target) or π/3 for component 3 (as a base) miss."""
    c2 = _problem(*_components(math.pi / 6, math.pi / 6)[2]).evaluate([TABLE_IV[2]["ga"][1]]).fitness[0]
    c3 = _problem(*_components(math.pi / 3, math.pi / 3)[3]).evaluate([TABLE_IV[3]["ga"][1]]).fitness[0]
    assert abs(c2 - 9.5612) < 1e-3 and abs(c3 - 8.5117) < 1e-3  # vs 10.78 and 5.107 printed


def test_matlab_style_is_about_0p1_percent_below_the_integral():
    base, target = _components(math.pi / 3, math.pi / 6)[1]
    problem = _problem(base, target)
    k = TABLE_IV[1]["woa"][1]
    matlab = problem.evaluate([k]).fitness[0]
    exact, err = problem.converged_fitness(k, n=2048)
    assert err < 1e-8
    assert 0.0005 < (exact - matlab) / exact < 0.002


def test_our_feasible_intervals_contain_table_iii_search_areas():
    task = maple_leaf_task()  # phase π/6 as printed
    ks = []
    for i in range(4):
        (lo, hi), = component_problem(task, i, ks).feasible_intervals()
        s_lo, s_hi = TABLE_III_SEARCH[i + 1]
        assert lo < s_lo and s_hi < hi
        ks.append(TABLE_IV[i + 1]["woa"][1])


@pytest.mark.parametrize("a6", [0.0, 10.0])
def test_printed_five_dof_case_is_infeasible(a6):
    for root in (1, -1):
        problem = component_problem(circle_task(knots="paper", root=root, a6=a6), 1, [])
        d = np.linalg.norm(problem.p_WT - problem.p_WB, axis=1)
        assert d.max() > 0.48 + 0.4
        if a6 == 0:
            assert abs(d[0] - 0.725) < 5e-4  # REFERENCES.md: 72.5 cm at t = 0
        assert problem.feasible_intervals() == []
