"""Per-generation overhead of an optimizer, excluding the objective.

The budget accounting and the algorithm's own numpy work are timed around a trivial
objective whose time is subtracted. The figure is "microseconds per ``pop_size``
evaluations", so methods that evaluate in smaller batches (ABC's two phases, GA's changed
individuals only) are compared per the same number of evaluations.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.optim import get_method


def measure_overhead(method: str, pop_size: int = 50, dim: int = 7, generations: int = 200,
                     repeats: int = 3, seed: int = 0) -> float:
    """Median over ``repeats`` of the optimizer time per ``pop_size`` evaluations [us].

    Args:
        method: an optimizer name.
        pop_size: population size P.
        dim: dimension D (box ``[-3, 3]^D``, like joint angles).
        generations: budget in units of P evaluations.
        repeats: independent timed runs; the median is returned (machines are noisy).
        seed: seed of the first run (run r uses ``seed + r``).

    Returns:
        Overhead in microseconds per P evaluations, objective excluded.
    """
    cls = get_method(method)
    lower, upper = np.full(dim, -3.0), np.full(dim, 3.0)
    budget = generations * pop_size
    times = []
    for r in range(repeats):
        opt = cls((lower, upper), budget=budget, seed=seed + r, pop_size=pop_size)
        t_f = 0.0
        t0 = time.perf_counter()
        while not opt.done:
            X = opt.ask()
            X = X[: opt.budget - opt.nfe]
            t1 = time.perf_counter()
            F = np.einsum("pd,pd->p", X, X)
            t_f += time.perf_counter() - t1
            opt.tell(X, F)
        total = time.perf_counter() - t0 - t_f
        times.append(total / (opt.nfe / pop_size) * 1e6)
    return float(np.median(times))
