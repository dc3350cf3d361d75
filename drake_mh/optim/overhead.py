"""Per-generation overhead of an optimizer, excluding the objective.

The ask and tell calls (budget accounting and the algorithm's numpy work) are timed around a trivial
objective that is not timed. The figure is "microseconds per ``pop_size``
evaluations", so methods that evaluate in smaller batches (ABC's two phases, GA's changed
individuals only) are compared per the same number of evaluations.
"""

from __future__ import annotations

import time

import numpy as np

from drake_mh.optim import get_method


def measure_overhead(method: str, pop_size: int = 50, dim: int = 7, generations: int = 200,
                     repeats: int = 3, seed: int = 0) -> float:
    """Optimizer time per ``pop_size`` evaluations [us], objective excluded.

    Every ask and every tell is timed on its own; the *median* call time (robust against
    other processes on a shared machine) is scaled to ``pop_size`` evaluations by the mean
    batch size, and the ask and tell medians are added.

    Args:
        method: an optimizer name.
        pop_size: population size P.
        dim: dimension D (box ``[-3, 3]^D``, like joint angles).
        generations: budget in units of P evaluations, per repeat.
        repeats: independent runs pooled (seeds ``seed, seed + 1, ...``).
        seed: seed of the first run.

    Returns:
        Overhead in microseconds per P evaluations.
    """
    cls = get_method(method)
    lower, upper = np.full(dim, -3.0), np.full(dim, 3.0)
    t_ask: list[float] = []
    t_tell: list[float] = []
    sizes: list[int] = []
    clock = time.perf_counter
    for r in range(repeats):
        opt = cls((lower, upper), budget=generations * pop_size, seed=seed + r, pop_size=pop_size)
        while not opt.done:
            t0 = clock()
            X = opt.ask()
            t1 = clock()
            X = X[: opt.budget - opt.nfe]
            F = np.einsum("pd,pd->p", X, X)
            t2 = clock()
            opt.tell(X, F)
            t3 = clock()
            t_ask.append(t1 - t0)
            t_tell.append(t3 - t2)
            sizes.append(len(X))
    per_call = float(np.median(t_ask) + np.median(t_tell))
    return per_call * pop_size / float(np.mean(sizes)) * 1e6
