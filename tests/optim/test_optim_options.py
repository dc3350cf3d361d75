"""Algorithm options and shared helpers."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_mh.optim import get_method, minimize
from drake_mh.optim.gsa import masses
from drake_mh.optim.testfunctions import make

F = make("rastrigin", 4, seed=11)


@pytest.mark.parametrize("method, params, tol", [
    ("ga", {"crossover": "sbx", "mutation": "polynomial"}, 5.0),
    ("ga", {"crossover": "sbx"}, 5.0),
    ("ga", {"mutation": "polynomial", "mutation_rate": 0.25}, 5.0),
    ("bat", {"beta_per_dimension": False}, 40.0),
    ("abc", {"limit": 20}, 1e-3),
    ("aro", {"variant": "amnn"}, 5.0),
    ("pso", {"w_start": 0.7, "w_end": 0.7, "c1": 1.5, "c2": 1.5}, 10.0),
    ("e3gsa", {"p_explore": 0.0}, 30.0),
    ("cmaes", {"restarts": False}, 30.0),
    ("de", {"F": 1.0}, 0.1),                          # NiaPy's default weight (docs/optimizers.md)
])
def test_options_run_and_converge(method, params, tol):
    budget = 8000 if method != "cmaes" else 3000
    res = minimize(F, F.bounds, method=method, budget=budget, seed=0, **params)
    assert res.nfe == budget
    assert F.error(res.f) <= tol


def test_cmaes_restarts_use_the_whole_budget():
    opt = get_method("cmaes")(([-1.0] * 3, [1.0] * 3), budget=6000, seed=0)
    while not opt.done:
        X = opt.ask()[: opt.budget - opt.nfe]
        opt.tell(X, np.sum((X - 0.2) ** 2, axis=1))
    assert opt.nfe == 6000 and opt.restarts >= 1


@settings(max_examples=40, deadline=None)
@given(n=st.integers(4, 60), seed=st.integers(0, 10**6), own=st.booleans())
def test_donors_are_distinct_and_exclude_self(n, seed, own):
    opt = get_method("de")(([0.0], [1.0]), budget=10, seed=seed, pop_size=4)
    r = opt.donors(n, n, exclude_self=own)
    assert r.shape == (n, 3) and r.min() >= 0 and r.max() < n
    assert all(len(set(row)) == 3 for row in r)
    if own:
        assert not np.any(r == np.arange(n)[:, None])


@settings(max_examples=40, deadline=None)
@given(x=st.lists(st.floats(-1e3, 1e3), min_size=3, max_size=3))
def test_reflect_and_reinit_stay_in_the_box(x):
    opt = get_method("random")(([-1.0, 0.0, 2.0], [1.0, 5.0, 2.5]), budget=10, seed=0)
    X = np.array([x])
    R = opt.reflect(X)
    assert np.all(R >= opt.lower) and np.all(R <= opt.upper)
    inside = (X >= opt.lower) & (X <= opt.upper)
    assert np.array_equal(R[inside], X[inside])
    Y = opt.reinit(X.copy())
    assert np.all(Y >= opt.lower) and np.all(Y <= opt.upper)
    assert np.array_equal(Y[inside], X[inside])


def test_gsa_masses():
    M = masses(np.array([1.0, 2.0, 3.0]))
    assert np.allclose(M, [2 / 3, 1 / 3, 0.0])
    assert np.allclose(masses(np.array([5.0, 5.0])), [0.5, 0.5])
    assert np.allclose(masses(np.array([1.0, np.inf, 3.0])), [1.0, 0.0, 0.0])
    assert np.allclose(masses(np.array([np.inf, np.inf])), [0.5, 0.5])


def test_population_of_result_is_sorted_for_ga_and_consistent():
    f = make("sphere", 3, seed=2)
    res = minimize(f, f.bounds, method="ga", budget=500, seed=0)
    assert np.all(np.diff(res.population_f) >= 0)
    assert np.allclose(f(res.population), res.population_f)
    assert res.population_f[0] == res.f


@pytest.mark.parametrize("method", ["pso", "bat", "gsa", "e3gsa", "woa", "ao", "abc", "aro", "de"])
def test_population_values_match_positions(method):
    f = make("sphere", 3, seed=2)
    res = minimize(f, f.bounds, method=method, budget=600, seed=0)
    assert np.allclose(f(res.population), res.population_f)
