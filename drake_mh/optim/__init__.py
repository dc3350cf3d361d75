"""Metaheuristic optimizers with an exact evaluation budget (ask/tell + ``minimize``).

Optimizers know nothing of robots: they minimize a vectorized objective
``f(X (P, D)) -> (P,)`` over a box. ``minimize(f, bounds, method, budget, seed)`` runs any
of :func:`available_methods`; the classes in :data:`METHODS` expose ask/tell.

Example:
    >>> import numpy as np
    >>> from drake_mh.optim import minimize
    >>> res = minimize(lambda X: np.sum((X - 0.3) ** 2, axis=1), [(-1, 1)] * 3,
    ...                method="de", budget=3000, seed=0)
    >>> bool(res.f < 1e-6), res.nfe
    (True, 3000)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from drake_mh._support.registry import Registry
from drake_mh.errors import NoFiniteValue
from drake_mh.optim.abc import ABC
from drake_mh.optim.ao import AO
from drake_mh.optim.aro import ARO
from drake_mh.optim.base import Optimizer, OptimizeResult, OptimizerState, as_bounds, run
from drake_mh.optim.bat import BAT
from drake_mh.optim.cmaes import CMAES
from drake_mh.optim.de import DE
from drake_mh.optim.e3gsa import E3GSA
from drake_mh.optim.ga import GA
from drake_mh.optim.gsa import GSA
from drake_mh.optim.pso import PSO
from drake_mh.optim.random_search import RandomSearch
from drake_mh.optim.woa import WOA, WOAGreedy

__all__ = [
    "METHODS",
    "OptimizeResult",
    "Optimizer",
    "OptimizerState",
    "as_bounds",
    "available_methods",
    "get_method",
    "minimize",
    "ABC", "AO", "ARO", "BAT", "CMAES", "DE", "E3GSA", "GA", "GSA", "PSO", "RandomSearch", "WOA", "WOAGreedy",
]

METHODS = Registry("optimizer", case_sensitive=False)
"""The optimizers of :func:`minimize`: name -> ask/tell class (:class:`~drake_mh._support.registry.Registry`,
case-insensitive); metaheuristics first, then the reference baselines."""
for _cls in (PSO, BAT, GSA, E3GSA, WOA, WOAGreedy, AO, GA, ABC, ARO, CMAES, DE, RandomSearch):
    METHODS.add(_cls.name, _cls, description=" ".join(_cls.__doc__.split("\n\n")[0].split()))
del _cls


def available_methods() -> list[str]:
    """Names accepted by :func:`minimize` (lowercase)."""
    return METHODS.names()


def get_method(name: str) -> type[Optimizer]:
    """The ask/tell class of a method name (case-insensitive).

    Raises:
        UnknownMethod: the name is not in :func:`available_methods`.
    """
    return METHODS.get(name)


def minimize(f: Callable[[np.ndarray], Any], bounds: Any, method: str = "pso", budget: int = 10_000,
             seed: Any = None, pop_size: int | None = None, target: float | None = None,
             callback: Callable[[OptimizerState], Any] | None = None, x0: Any = None,
             **params: Any) -> OptimizeResult:
    """Minimizes a vectorized objective over a box with an exact evaluation budget.

    Args:
        f: objective, ``f(X (P, D)) -> (P,)`` real values; NaN counts as +inf; -inf is the
            minimum there is: the run ends at the first point that scores it (``x``, ``f = -inf``).
        bounds: ``(D, 2)`` array of ``[lower, upper]`` rows, or a tuple ``(lower, upper)``.
        method: one of :func:`available_methods`.
        budget: function evaluations; never exceeded, and all used unless ``target`` or
            ``callback`` stops the run.
        seed: seed of ``numpy.random.default_rng``; same seed gives a bit-identical result.
        pop_size: population size (``None``: the method's default).
        target: stop as soon as the best value is ``<= target``.
        callback: called with an :class:`OptimizerState` after every generation; a truthy
            return value stops the run.
        x0: ``(D,)`` or ``(K, D)`` points injected into the initial population.
        **params: the method's hyper-parameters (fields of ``get_method(method).Config``).

    Returns:
        OptimizeResult: ``x, f, nfe, nit, time, message, history, method, seed`` and the
        final population (for warm starts).

    Raises:
        UnknownMethod: unknown ``method``.
        InvalidArgument: bad bounds, budget, pop_size, x0, target or hyper-parameters.
        InvalidObjective: ``f`` does not return real values of shape ``(P,)``, or modifies ``X``
            in place.
        NoFiniteValue: ``f`` returned NaN or +inf at every evaluated point (no best point).
    """
    cls = get_method(method)
    opt = cls(bounds, budget=budget, seed=seed, pop_size=pop_size, x0=x0, **params)
    result = run(opt, f, target=target, callback=callback)
    if not result.f < np.inf:  # -inf is a minimum
        raise NoFiniteValue(
            f"{method}: the objective returned NaN or +inf at all {result.nfe} evaluated points, so "
            "there is no best point; return finite values (e.g. a large penalty instead of inf or "
            "NaN) or raise the budget if finite values are rare")
    return result
