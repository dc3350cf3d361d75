"""Optimizers under bad input and misbehaving objectives (reliability issue, items 10, 13, 17)."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.errors import AskTellError, InvalidArgument, InvalidObjective, NoFiniteValue
from drake_mh.optim import available_methods, get_method, minimize

BOUNDS = [(-1.0, 1.0)] * 3


def sphere(X):
    return np.sum(X**2, axis=1)


@pytest.mark.parametrize("method", ["pso", "ga", "cmaes"])
def test_objective_writing_into_X_gets_a_clear_error(method):
    def clobber(X):
        X += 5.0
        return sphere(X)

    with pytest.raises(InvalidObjective, match="in place"):
        minimize(clobber, BOUNDS, method=method, budget=200, seed=0)


def test_result_x_is_the_point_that_scored_f():
    res = minimize(sphere, BOUNDS, method="pso", budget=500, seed=0)
    assert res.f == pytest.approx(float(sphere(res.x[None])[0]), abs=0)


@pytest.mark.parametrize("value", [np.nan, np.inf])
@pytest.mark.parametrize("method", available_methods())
def test_no_finite_value_raises(method, value):
    with pytest.raises(NoFiniteValue, match="no best point"):
        minimize(lambda X: np.full(len(X), value), BOUNDS, method=method, budget=120, seed=0)


def test_bounds_whose_width_overflows_are_rejected():
    with pytest.raises(InvalidArgument, match="too wide"):
        minimize(sphere, [(-1e308, 1e308)] * 2, method="pso", budget=100, seed=0)


@pytest.mark.parametrize("seed", ["abc", 1.5, -1, True, 1j])
def test_bad_seeds_are_named(seed):
    with pytest.raises(InvalidArgument, match="seed must be"):
        minimize(sphere, BOUNDS, method="de", budget=100, seed=seed)


def test_tell_with_other_candidates_is_refused():
    opt = get_method("pso")(BOUNDS, budget=100, seed=0)
    X = opt.ask()
    with pytest.raises(AskTellError, match="other candidates"):
        opt.tell(X + 0.1, sphere(X + 0.1))
    opt.tell(X, sphere(X))                      # the refused call changed nothing
    assert opt.nfe == len(X)


@pytest.mark.parametrize("method", ["pso", "de", "cmaes"])
def test_complex_objective_values_are_refused(method):
    """numpy kept the real part with only a warning: the run minimized something else."""
    with pytest.raises(InvalidObjective, match="complex"):
        minimize(lambda X: sphere(X) + 1j * X[:, 0], BOUNDS, method=method, budget=100, seed=0)
    opt = get_method(method)(BOUNDS, budget=100, seed=0)
    X = opt.ask()
    with pytest.raises(InvalidObjective, match="complex"):
        opt.tell(X, sphere(X) + 0j)


@pytest.mark.parametrize("method", available_methods())
def test_minus_infinity_is_the_minimum_it_is(method):
    """-inf in part of the box: the first point that scores it is the answer, and the run ends
    there (it used to raise NoFiniteValue saying 'NaN or +inf at all 400 evaluated points')."""

    def cliff(X):
        return np.where(X[:, 0] > 0.5, -np.inf, sphere(X))

    res = minimize(cliff, BOUNDS, method=method, budget=4000, seed=0)
    assert res.f == -np.inf and res.x[0] > 0.5 and cliff(res.x[None])[0] == -np.inf
    assert res.nfe < 4000 and "-inf" in res.message
    opt = get_method(method)(BOUNDS, budget=1000, seed=0)  # ask/tell: the run is over after the tell
    X = opt.ask()
    opt.tell(X, np.full(len(X), -np.inf))
    assert opt.done and opt.result().f == -np.inf
    with pytest.raises(AskTellError, match="-inf"):
        opt.ask()
