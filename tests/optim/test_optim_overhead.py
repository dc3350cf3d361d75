"""The overhead meter and its plain-numpy reference follow their stated protocol (not timed: a
fake clock makes every timed part last exactly one microsecond)."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest

from drake_mh.optim import get_method
from drake_mh.optim.overhead import measure_overhead, measure_reference_us


@pytest.fixture
def microsecond_clock(monkeypatch):
    """``time.perf_counter`` advancing by exactly 1 µs per call."""
    ticks = itertools.count()
    monkeypatch.setattr(time, "perf_counter", lambda: next(ticks) * 1e-6)


def _mean_batch(method, pop_size, dim, generations, repeats, seed=0) -> float:
    """Mean number of evaluations per tell, from the optimizer's own ask/tell loop."""
    sizes = []
    for r in range(repeats):
        opt = get_method(method)((np.full(dim, -3.0), np.full(dim, 3.0)), budget=generations * pop_size,
                                 seed=seed + r, pop_size=pop_size)
        while not opt.done:
            X = opt.ask()[: opt.budget - opt.nfe]
            opt.tell(X, np.einsum("pd,pd->p", X, X))
            sizes.append(len(X))
    return float(np.mean(sizes))


@pytest.mark.parametrize("method", ["random", "abc", "ga", "de"])
def test_overhead_is_the_median_call_time_per_pop_size_evaluations(microsecond_clock, method):
    """One timed ask and one timed tell of 1 µs each: 2 µs per call, scaled to ``pop_size``
    evaluations by the mean batch size (ABC's phases and GA's changed individuals evaluate
    fewer than ``pop_size`` at a time)."""
    us = measure_overhead(method, pop_size=10, dim=3, generations=5, repeats=2)
    assert us == pytest.approx(2.0 * 10 / _mean_batch(method, 10, 3, 5, 2), rel=1e-9)
    assert method in ("random", "de") or us > 2.0 + 1e-9  # the methods with smaller batches are scaled


def test_reference_is_its_two_timed_parts(microsecond_clock):
    assert measure_reference_us(pop_size=10, dim=3, generations=5, repeats=2) == pytest.approx(2.0, rel=1e-9)


def test_real_clock_gives_finite_positive_microseconds():
    us = measure_overhead("random", pop_size=10, dim=3, generations=5, repeats=1)
    ref = measure_reference_us(pop_size=10, dim=3, generations=5, repeats=1)
    assert math.isfinite(us) and math.isfinite(ref) and us > 0.0 and ref > 0.0
