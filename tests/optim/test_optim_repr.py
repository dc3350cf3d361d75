"""OptimizeResult prints in a few lines (no history rows, x summarized)."""

from __future__ import annotations

import numpy as np

import drake_mh
from drake_mh.optim.base import summarize_array


def _sphere(X):
    return np.sum(X**2, axis=1)


def test_result_repr_is_short_and_names_the_run():
    result = drake_mh.minimize(_sphere, [(-1.0, 1.0)] * 40, method="pso", budget=800, seed=3)
    text = repr(result)
    assert len(text.splitlines()) <= 5 and len(text) < 600
    assert str(result) == text
    assert "method='pso'" in text and "seed=3" in text and f"nfe = {result.nfe}" in text
    assert f"f = {result.f:.6g}" in text and "(D = 40)" in text and "..." in text
    assert f"{len(result.history)} rows" in text


def test_small_x_is_printed_whole():
    assert summarize_array(np.array([1.0, 2.5])) == "[1. , 2.5]"
    long = summarize_array(np.arange(100.0))
    assert "..." in long and "99." in long and "\n" not in long
