"""Per-generation overhead of an optimizer, excluding the objective, and a same-run yardstick.

The ask and tell calls (budget accounting and the algorithm's own work) are timed around a
trivial objective that is not timed. The figure is "microseconds per ``pop_size``
evaluations", so methods that evaluate in smaller batches (ABC's two phases, GA's changed
individuals only) are compared per the same number of evaluations.

Absolute microseconds depend on the machine and on what else runs on it. A report should
print the overhead next to :func:`measure_reference_us`, a fixed plain-numpy generation
timed with the same protocol in the same run, and their ratio: both figures are made of the
same kind of cost (interpreter and small-numpy-call overhead), so the ratio is less
sensitive to the machine's speed and load than either figure.
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


def measure_reference_us(pop_size: int = 50, dim: int = 7, generations: int = 200,
                         repeats: int = 3, seed: int = 0) -> float:
    """Time of a fixed plain-numpy "generation" [us], the yardstick for :func:`measure_overhead`.

    One reference generation on the box ``[-3, 3]^D`` (``lower``, ``upper``, ``width``
    ``(D,)`` arrays) with ``rng = numpy.random.default_rng(seed + repeat)`` is two timed
    parts, mirroring ask and tell::

        X = lower + rng.random((P, D)) * width      # "ask": draw a population, scale it
        np.maximum(X, lower, out=X)                 #        into the box and clip it
        np.minimum(X, upper, out=X)                 #        (as Optimizer.clip does)
        int(np.argmin(F))                           # "tell": best of a fixed (P,) vector F

    ``F`` is one ``rng.random(P)`` drawn before the timing. As in :func:`measure_overhead`,
    each part is timed on its own over ``generations`` generations per repeat, and the
    medians of the two parts are added. The work is a handful of small numpy calls, so it
    scales with the interpreter and numpy call overhead, as the optimizers' overhead does.

    Args:
        pop_size: population size P.
        dim: dimension D.
        generations: timed generations per repeat.
        repeats: repeats pooled (seeds ``seed, seed + 1, ...``).
        seed: seed of the first repeat.

    Returns:
        Microseconds per reference generation.
    """
    lower, upper = np.full(dim, -3.0), np.full(dim, 3.0)
    width = upper - lower
    t_ask: list[float] = []
    t_tell: list[float] = []
    clock = time.perf_counter
    for r in range(repeats):
        rng = np.random.default_rng(seed + r)
        F = rng.random(pop_size)
        for _ in range(generations):
            t0 = clock()
            X = lower + rng.random((pop_size, dim)) * width
            np.maximum(X, lower, out=X)
            np.minimum(X, upper, out=X)
            t1 = clock()
            t2 = clock()
            int(np.argmin(F))
            t3 = clock()
            t_ask.append(t1 - t0)
            t_tell.append(t3 - t2)
    return float(np.median(t_ask) + np.median(t_tell)) * 1e6
