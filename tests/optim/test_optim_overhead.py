"""The overhead meter and its plain-numpy reference run and return sane figures (not timed)."""

from __future__ import annotations

import math

import pytest

from drake_mh.optim.overhead import measure_overhead, measure_reference_us


@pytest.mark.parametrize("method", ["random", "abc"])
def test_overhead_and_reference_are_positive_microseconds(method):
    us = measure_overhead(method, pop_size=10, dim=3, generations=5, repeats=1)
    ref = measure_reference_us(pop_size=10, dim=3, generations=5, repeats=1)
    assert math.isfinite(us) and math.isfinite(ref)
    assert 0.0 < us < 1e6 and 0.0 < ref < 1e6
