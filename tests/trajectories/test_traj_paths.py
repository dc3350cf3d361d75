"""The joint path's spline: the not-a-knot fit equals scipy's CubicSpline, extrema are exact."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline

from drake_mh.trajectories.paths import not_a_knot, piece_extrema


@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 30), nq=st.integers(1, 9), seed=st.integers(0, 2 ** 31))
def test_not_a_knot_is_scipys_spline(n, nq, seed):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(n, nq))
    s = np.r_[0.0, np.cumsum(rng.uniform(1e-3, 2.0, n - 1))]
    ours, scipys = not_a_knot(s, P), CubicSpline(s, P)
    assert type(ours) is CubicSpline and ours.c.shape == scipys.c.shape
    np.testing.assert_array_equal(ours.x, scipys.x)
    scale = max(1.0, float(np.max(np.abs(scipys.c))))
    np.testing.assert_allclose(ours.c, scipys.c, rtol=0, atol=1e-11 * scale)
    t = np.linspace(s[0], s[-1], 101)
    np.testing.assert_allclose(ours(t), scipys(t), atol=1e-11 * scale)
    np.testing.assert_allclose(ours(s), P, atol=1e-11 * scale)  # it interpolates


def test_two_points_give_the_line():
    P = np.array([[0.0, 1.0], [2.0, -1.0]])
    spline = not_a_knot(np.array([0.0, 2.0]), P)
    t = np.linspace(0.0, 2.0, 7)
    np.testing.assert_allclose(spline(t), P[0] + (t / 2.0)[:, None] * (P[1] - P[0]), atol=1e-15)
    np.testing.assert_allclose(spline(t, 2), 0.0, atol=1e-15)


@pytest.mark.parametrize("seed", range(5))
def test_piece_extrema_bound_dense_samples_and_are_reached(seed):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(6, 3))
    spline = not_a_knot(np.r_[0.0, np.cumsum(rng.uniform(0.1, 1.0, 5))], P)
    lo, hi = piece_extrema(spline)
    for i in range(5):
        v = spline(np.linspace(spline.x[i], spline.x[i + 1], 4001))
        assert np.all(v.min(axis=0) >= lo[i] - 1e-12) and np.all(v.max(axis=0) <= hi[i] + 1e-12)
        np.testing.assert_allclose(v.min(axis=0), lo[i], atol=1e-6)  # exact, seen by dense samples
        np.testing.assert_allclose(v.max(axis=0), hi[i], atol=1e-6)
