"""Each method reaches a *stated* tolerance on shifted problems within a stated budget.

Problems: D = 5 on the box [-100, 100]^5 (CEC scaling), optimum drawn away from the origin
and the box centre (``make(..., shift="random", seed=7)``): sphere, Rastrigin (multimodal)
and Rosenbrock (curved valley). Budget 10 000 evaluations (CMA-ES 4 000: pycma costs ~2 ms
per generation). Statistic: median error of seeds 0, 1, 2 (deterministic).

The tolerances are honest, per method: weak methods get loose ones (AO and GSA do not
converge on *shifted* problems at all - the centre bias of Kudela 2022 - and are only
required to stay near random-search level there). Measured medians when the table was
set are in the comments (error = f - f_opt).
"""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.optim import available_methods, minimize
from drake_mh.optim.testfunctions import make

D = 5
SEEDS = (0, 1, 2)

# method: (sphere, rastrigin, rosenbrock) tolerance on the median error
TOLERANCES = {
    "pso": (1e-9, 5.0, 2.0),          # measured 3e-12, 1.0, 0.22
    "bat": (1.0, 60.0, 5.0),          # 0.10, 19, 0.20
    "gsa": (2e3, 60.0, 50.0),         # 1.9e2, 22, 10   (centre bias: unshifted sphere 2e-18)
    "e3gsa": (1e-12, 25.0, 2.0),      # 4e-19, 5.0, 0.24
    "woa": (5e2, 40.0, 30.0),         # 41, 10, 3.3     (centre bias: unshifted sphere 7e-59)
    "woa_greedy": (1e-3, 40.0, 15.0), # 9.8e-6, 17, 1.6 (mealpy's variant; unshifted sphere 1e-67)
    "ao": (1e4, 50.0, 200.0),         # 1.2e3, 8.0, 41  (centre bias: unshifted sphere 1e-5)
    "ga": (0.1, 0.1, 10.0),           # 7.8e-3, 4.4e-3, 1.2
    "abc": (1e-12, 1e-6, 0.2),        # 1.6e-18, 7e-15, 0.012
    "aro": (1e-3, 0.1, 3.0),          # 1.5e-5, 1.3e-3, 0.42
    "cmaes": (1e-10, 25.0, 1e-8),     # 3.8e-15, 7.0, 4e-15  (4 000 evaluations)
    "de": (1e-10, 15.0, 1.0),         # 6e-15, 2.8, 0.085
    "random": (2e3, 40.0, 50.0),      # 6.0e2, 19, 17
}
FUNCTIONS = ("sphere", "rastrigin", "rosenbrock")


def budget_of(method: str) -> int:
    return 4000 if method == "cmaes" else 10000


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


def test_metaheuristics_beat_random_search_where_they_should():
    rnd = [median_error("random", n) for n in FUNCTIONS]
    for method in ("pso", "e3gsa", "abc", "aro", "de", "ga"):
        for name, r in zip(FUNCTIONS, rnd):
            assert median_error(method, name) < r, (method, name)


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
