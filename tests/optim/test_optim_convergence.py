"""Each method reaches a *stated* tolerance on shifted problems within a stated budget.

Problems: D = 5 on the box [-100, 100]^5 (CEC scaling), optimum drawn away from the origin
and the box centre (``make(..., shift="random", seed=7)``): sphere, Rastrigin (multimodal)
and Rosenbrock (curved valley). Budget 10 000 evaluations (CMA-ES 4 000: pycma costs ~2 ms
per generation). Statistic: median error of seeds 0, 1, 2 (deterministic).

The tolerances are about three times the measured medians (in the comments; error =
f - f_opt), so that a method that gets three times worse fails. Where a method stands against
random search is stated separately for every method and function (``RELATIVE_TO_RANDOM``): AO
is *worse* than random search on the shifted sphere and Rosenbrock (the centre bias of Kudela
2022: it solves the unshifted sphere), which its tolerance alone would not show.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from drake_mh.optim import available_methods, minimize
from drake_mh.optim.testfunctions import make

D = 5
SEEDS = (0, 1, 2)

# method: (sphere, rastrigin, rosenbrock) tolerance on the median error
TOLERANCES = {
    "pso": (1e-11, 3.0, 0.7),         # measured 3.3e-12, 1.0, 0.22
    "bat": (0.5, 60.0, 0.7),          # 0.10, 19, 0.20
    "gsa": (1e3, 50.0, 20.0),         # 3.4e2, 17, 5.3   (centre bias: unshifted sphere 2e-18)
    "e3gsa": (1e-18, 10.0, 1.0),      # 1.6e-19, 3.0, 0.24
    "woa": (100.0, 30.0, 10.0),       # 26, 9.3, 3.2     (centre bias: unshifted sphere 7e-59)
    "woa_greedy": (5e-5, 50.0, 5.0),  # 9.8e-6, 17, 1.6 (mealpy's variant; unshifted sphere 1e-67)
    "ao": (6e3, 35.0, 90.0),          # 2.0e3, 11, 29   (centre bias: unshifted sphere 1e-5)
    "ga": (0.03, 0.015, 4.0),         # 7.8e-3, 4.4e-3, 1.2
    "abc": (1e-17, 1e-13, 0.04),      # 1.6e-18, 7.1e-15, 0.012
    "aro": (5e-6, 4e-3, 1.0),         # 1.3e-6, 1.1e-3, 0.31
    "cmaes": (1e-14, 25.0, 1e-14),    # 1.8e-15, 7.0, 3.5e-15  (4 000 evaluations)
    "de": (1e-14, 10.0, 0.1),         # 1.6e-15, 3.1, 0.030
    "random": (2e3, 60.0, 60.0),      # 6.0e2, 19, 17
}
FUNCTIONS = ("sphere", "rastrigin", "rosenbrock")

# method: against random search's median on (sphere, rastrigin, rosenbrock): "<" better, ">" worse,
# "~" within a factor 2 either way (measured with the medians above)
RELATIVE_TO_RANDOM = {
    "pso": "<<<", "bat": "<~<", "gsa": "<~<", "e3gsa": "<<<", "woa": "<<<", "woa_greedy": "<~<", "ao": "><>",
    "ga": "<<<", "abc": "<<<", "aro": "<<<", "cmaes": "<<<", "de": "<<<",
}


def budget_of(method: str) -> int:
    return 4000 if method == "cmaes" else 10000


@functools.lru_cache(maxsize=None)
def median_error(method: str, name: str, shift="random") -> float:
    f = make(name, D, shift=shift, seed=7)
    errs = [f.error(minimize(f, f.bounds, method=method, budget=budget_of(method), seed=s).f) for s in SEEDS]
    return float(np.median(errs))


def test_every_method_has_a_stated_tolerance():
    assert set(TOLERANCES) == set(available_methods())


def test_problems_are_shifted_away_from_centre_and_origin():
    for name in FUNCTIONS:
        f = make(name, D, seed=7)
        assert np.all(np.abs(f.x_opt) >= 0.3 * 100.0)


@pytest.mark.parametrize("method", available_methods())
@pytest.mark.parametrize("k, name", list(enumerate(FUNCTIONS)))
def test_reaches_stated_tolerance(method, k, name):
    err = median_error(method, name)
    assert err <= TOLERANCES[method][k], f"{method} on shifted {name}: median error {err:.3g}"


def test_every_method_has_a_stated_standing_against_random_search():
    assert set(RELATIVE_TO_RANDOM) == set(available_methods()) - {"random"}


@pytest.mark.parametrize("method", sorted(RELATIVE_TO_RANDOM))
def test_standing_against_random_search(method):
    """Better, worse, or within a factor 2 of random search's median, as stated per function."""
    for name, relation in zip(FUNCTIONS, RELATIVE_TO_RANDOM[method]):
        ratio = median_error(method, name) / median_error("random", name)
        if relation == "<":
            assert ratio < 1.0, (method, name, ratio)
        elif relation == ">":
            assert ratio > 1.0, (method, name, ratio)
        else:
            assert 0.5 <= ratio <= 2.0, (method, name, ratio)


@pytest.mark.parametrize("method", ["woa", "woa_greedy", "ao", "gsa"])
def test_centre_bias_is_reproduced(method):
    """Characterization (Kudela 2022): these methods solve the *unshifted* sphere (optimum at
    the box centre) many orders of magnitude better than the same sphere shifted."""
    unshifted = median_error(method, "sphere", shift="none")
    shifted = median_error(method, "sphere")
    assert unshifted < 1e-3 * shifted, (method, unshifted, shifted)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["pso", "de", "abc", "e3gsa", "cmaes"])
def test_rotated_rastrigin_d10(method):
    """Rotation removes separability: the strong methods still get near a good basin."""
    f = make("rastrigin", 10, rotate=True, seed=3)
    res = minimize(f, f.bounds, method=method, budget=30000 if method != "cmaes" else 10000, seed=0)
    assert f.error(res.f) <= 60.0
