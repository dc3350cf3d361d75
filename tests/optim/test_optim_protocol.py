"""Protocol tests every optimizer must pass: determinism, exact budget, bounds, ask/tell."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import drake_mh
from drake_mh.errors import AskTellError, InvalidArgument, InvalidObjective, UnknownMethod
from drake_mh.optim import METHODS, OptimizeResult, available_methods, get_method, minimize

ALL = available_methods()
FAST = [m for m in ALL if m != "cmaes"]  # pycma costs ~2 ms per generation

SHIFT = np.array([3.1, -1.7, 0.9, 2.4])
LOWER = np.array([-4.0, -2.0, -1.0, 0.5])
UPPER = np.array([5.0, 1.0, 3.0, 6.0])


def sphere(X):
    return np.sum((X - SHIFT) ** 2, axis=1)


class Recorder:
    """Vectorized objective that records every evaluated row."""

    def __init__(self, f=sphere):
        self.f = f
        self.rows = []

    def __call__(self, X):
        assert X.ndim == 2
        self.rows.append(np.array(X, copy=True))
        return self.f(X)

    @property
    def X(self):
        return np.concatenate(self.rows) if self.rows else np.empty((0, len(SHIFT)))


def test_available_methods_lists_all_required_names():
    required = {"pso", "bat", "gsa", "e3gsa", "woa", "woa_greedy", "ao", "ga", "abc", "aro", "cmaes", "de", "random"}
    assert required == set(ALL)
    assert all(m == m.lower() for m in ALL)


@pytest.mark.parametrize("method", ALL)
def test_same_seed_gives_bit_identical_result(method):
    budget = 600 if method != "cmaes" else 300
    a = minimize(sphere, (LOWER, UPPER), method=method, budget=budget, seed=123)
    b = minimize(sphere, (LOWER, UPPER), method=method, budget=budget, seed=123)
    c = minimize(sphere, (LOWER, UPPER), method=method, budget=budget, seed=124)
    assert np.array_equal(a.x, b.x) and a.f == b.f
    assert np.array_equal(a.history, b.history)
    assert a.nit == b.nit and a.nfe == b.nfe
    assert not np.array_equal(a.history, c.history)


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("budget", [1, 7, 103, 517])
def test_budget_is_used_exactly_and_bounds_hold(method, budget):
    rec = Recorder()
    res = minimize(rec, (LOWER, UPPER), method=method, budget=budget, seed=0)
    X = rec.X
    assert res.nfe == budget == len(X)
    assert np.all(X >= LOWER) and np.all(X <= UPPER)
    assert res.f == pytest.approx(float(np.min(sphere(X))))
    assert np.all(res.x >= LOWER) and np.all(res.x <= UPPER)
    assert res.history[-1, 0] == budget and res.history[-1, 1] == res.f
    assert np.all(np.diff(res.history[:, 0]) > 0) and np.all(np.diff(res.history[:, 1]) <= 0)
    assert res.message == "budget exhausted" and res.method == method and res.seed == 0


@pytest.mark.parametrize("method", ALL)
def test_bounds_hold_when_the_optimum_is_outside_the_box(method):
    # a linear objective drives every method into the corner at the lower bounds
    rec = Recorder(lambda X: np.sum(X, axis=1))
    res = minimize(rec, (LOWER, UPPER), method=method, budget=800 if method != "cmaes" else 300, seed=3)
    X = rec.X
    assert np.all(X >= LOWER) and np.all(X <= UPPER)
    assert res.f >= np.sum(LOWER)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(method=st.sampled_from(FAST), budget=st.integers(1, 400), pop=st.integers(4, 30),
       seed=st.integers(0, 2**32 - 1))
def test_budget_property(method, budget, pop, seed):
    rec = Recorder()
    res = minimize(rec, (LOWER, UPPER), method=method, budget=budget, seed=seed, pop_size=pop)
    assert res.nfe == budget == len(rec.X)
    assert np.all(rec.X >= LOWER) and np.all(rec.X <= UPPER)


@pytest.mark.parametrize("method", ALL)
def test_ask_tell_run_equals_minimize(method):
    budget = 437 if method != "cmaes" else 211
    ref = minimize(sphere, (LOWER, UPPER), method=method, budget=budget, seed=9)
    opt = get_method(method)((LOWER, UPPER), budget=budget, seed=9)
    while not opt.done:
        X = opt.ask()
        X = X[: opt.budget - opt.nfe]
        opt.tell(X, sphere(X))
    res = opt.result()
    assert np.array_equal(res.x, ref.x) and res.f == ref.f and res.nfe == ref.nfe == budget
    assert np.array_equal(res.history, ref.history)
    with pytest.raises(AskTellError):
        opt.ask()


@pytest.mark.parametrize("method", ALL)
def test_x0_is_injected_into_the_first_population(method):
    # the last row sits on the bounds, where a bound transform (cmaes) must still hit it exactly
    x0 = np.array([[3.0, -1.5, 1.0, 2.5], [0.0, 0.0, 0.0, 1.0], [5.0, -2.0, 3.0, 0.5]])
    rec = Recorder()
    res = minimize(rec, (LOWER, UPPER), method=method, budget=200, seed=1, x0=x0)
    first = rec.rows[0]
    for row in x0:
        assert np.any(np.all(np.isclose(first, row, rtol=0, atol=1e-12), axis=1)), (method, row)
    assert res.f <= float(sphere(x0[:1])[0])


@pytest.mark.parametrize("method", FAST)
def test_single_x0_at_the_optimum_is_kept(method):
    res = minimize(sphere, (LOWER, UPPER), method=method, budget=300, seed=2, x0=SHIFT)
    assert res.f == 0.0 and np.array_equal(res.x, SHIFT)


def test_x0_outside_the_box_is_clipped():
    rec = Recorder()
    minimize(rec, (LOWER, UPPER), method="pso", budget=50, seed=0, x0=[100.0, 0.0, 0.0, 1.0])
    assert np.array_equal(rec.rows[0][0], [5.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize("variant", ["aro", "amnn"])
def test_aro_warm_start_from_a_previous_population(variant):
    f = lambda X: np.sum((X - SHIFT) ** 2, axis=1) + np.sum(np.cos(3 * X), axis=1)  # noqa: E731
    first = minimize(f, (LOWER, UPPER), method="aro", budget=1500, seed=4, variant=variant)
    assert first.population.shape == (50, 4) and first.population_f.shape == (50,)
    rec = Recorder(f)
    second = minimize(rec, (LOWER, UPPER), method="aro", budget=500, seed=5, variant=variant,
                      x0=first.population)
    assert np.array_equal(rec.rows[0], first.population)       # the whole population carries over
    assert second.history[0, 1] == pytest.approx(first.f)       # best after the first layer
    assert second.f <= first.f


def test_target_and_callback_stop_early():
    res = minimize(sphere, (LOWER, UPPER), method="de", budget=20000, seed=0, target=1e-3)
    assert res.message == "target reached" and res.success
    assert res.f <= 1e-3 and res.nfe < 20000
    calls = []
    res = minimize(sphere, (LOWER, UPPER), method="pso", budget=20000, seed=0,
                   callback=lambda s: calls.append(s.nfe) or s.nit >= 5)
    assert res.message == "stopped by callback" and res.nit == 5 and calls[-1] == res.nfe


def test_nan_values_count_as_worst():
    def f(X):
        F = sphere(X)
        F[::2] = np.nan
        return F

    for method in ("pso", "gsa", "abc", "cmaes"):
        res = minimize(f, (LOWER, UPPER), method=method, budget=300, seed=0)
        assert np.isfinite(res.f), method


def test_result_is_frozen_and_top_level_reexports():
    res = drake_mh.minimize(sphere, (LOWER, UPPER), method="random", budget=10, seed=0)
    assert isinstance(res, drake_mh.OptimizeResult) and isinstance(res, OptimizeResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.f = 0.0
    assert res.history.shape[1] == 2 and res.time >= 0


@pytest.mark.parametrize("method", FAST)
def test_one_dimensional_problems(method):
    res = minimize(lambda X: (X[:, 0] - 0.3) ** 2, [(-1.0, 1.0)], method=method, budget=300, seed=0)
    assert res.x.shape == (1,) and res.nfe == 300 and -1 <= res.x[0] <= 1


def test_bounds_forms_are_equivalent():
    B = np.stack([LOWER, UPPER], axis=1)
    a = minimize(sphere, B, method="pso", budget=200, seed=0)
    b = minimize(sphere, (LOWER, UPPER), method="pso", budget=200, seed=0)
    c = minimize(sphere, [tuple(r) for r in B], method="pso", budget=200, seed=0)
    assert a.f == b.f == c.f


# --- errors -------------------------------------------------------------------------------


def test_unknown_method_lists_the_valid_names():
    with pytest.raises(UnknownMethod) as e:
        minimize(sphere, (LOWER, UPPER), method="nope", budget=10)
    assert "pso" in str(e.value) and "cmaes" in str(e.value)
    assert set(e.value.available) == set(METHODS)


@pytest.mark.parametrize("bounds, fragment", [
    (np.zeros((3, 3)), "shape (D, 2)"),
    ([[1.0, 0.0]], "lower < upper"),
    ([[0.0, 0.0]], "lower < upper"),
    ([[0.0, np.inf]], "finite"),
    ([[np.nan, 1.0]], "finite"),
    (([0.0, 0.0], [1.0]), "same length"),
    ("abc", "(D, 2)"),
    (np.empty((0, 2)), "shape (D, 2)"),
])
def test_bad_bounds_say_how_to_fix(bounds, fragment):
    with pytest.raises(InvalidArgument) as e:
        minimize(sphere, bounds, method="pso", budget=10)
    assert fragment in str(e.value)


@pytest.mark.parametrize("budget", [0, -5, 1.5, True, "100", None])
def test_bad_budget(budget):
    with pytest.raises(InvalidArgument, match="budget"):
        minimize(sphere, (LOWER, UPPER), method="pso", budget=budget)


def test_bad_pop_size_x0_and_params():
    with pytest.raises(InvalidArgument, match="pop_size"):
        minimize(sphere, (LOWER, UPPER), method="de", budget=10, pop_size=3)
    with pytest.raises(InvalidArgument, match="x0"):
        minimize(sphere, (LOWER, UPPER), method="de", budget=10, x0=[1.0, 2.0])
    with pytest.raises(InvalidArgument, match="x0"):
        minimize(sphere, (LOWER, UPPER), method="de", budget=10, pop_size=4, x0=np.zeros((5, 4)))
    with pytest.raises(InvalidArgument, match="valid parameters: w_start"):
        minimize(sphere, (LOWER, UPPER), method="pso", budget=10, inertia=0.5)
    with pytest.raises(InvalidArgument, match="crossover"):
        minimize(sphere, (LOWER, UPPER), method="ga", budget=10, crossover="uniform")
    with pytest.raises(InvalidArgument, match="variant"):
        minimize(sphere, (LOWER, UPPER), method="aro", budget=10, variant="gpu")
    with pytest.raises(InvalidArgument, match="D >= 2"):
        minimize(lambda X: X[:, 0], [(0, 1)], method="cmaes", budget=10)


def test_objective_with_wrong_shape_is_reported():
    with pytest.raises(InvalidObjective, match=r"must return shape \(P,\)"):
        minimize(lambda X: np.sum(X), (LOWER, UPPER), method="pso", budget=100)
    with pytest.raises(InvalidObjective):
        minimize(lambda X: X, (LOWER, UPPER), method="pso", budget=100)


def test_ask_tell_misuse():
    opt = get_method("pso")((LOWER, UPPER), budget=100, seed=0)
    with pytest.raises(AskTellError, match="ask"):
        opt.tell(np.zeros((1, 4)), [0.0])
    X = opt.ask()
    with pytest.raises(AskTellError, match="twice"):
        opt.ask()
    with pytest.raises(AskTellError):
        opt.tell(X[:, :2], sphere(X))
    opt.tell(X[:3], sphere(X[:3]))         # a partial tell ends the run
    assert opt.done and opt.nfe == 3
    with pytest.raises(AskTellError, match="over"):
        opt.ask()
