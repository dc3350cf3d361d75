"""The joint path's spline: the not-a-knot fit equals scipy's CubicSpline, extrema are exact."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline

from drake_mh._support.native import compiled_core
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


CORE = compiled_core()
needs_core = pytest.mark.skipif(CORE is None, reason="the compiled core drake_mh._native is not built")


@needs_core
@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 30), nq=st.integers(1, 9), seed=st.integers(0, 2 ** 31))
def test_compiled_cubic_path_is_scipys_spline_and_its_extrema(n, nq, seed):
    """The core's ``cubic_path`` (the joint path's fit and extrema in one call): scipy's
    not-a-knot spline to round-off (amplified by knots 1e-3 to 2 apart) and the extrema of
    :func:`piece_extrema` on it."""
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(n, nq))
    s = np.r_[0.0, np.cumsum(rng.uniform(1e-3, 2.0, n - 1))]
    c, lo, hi = CORE.cubic_path(s, P)
    scipys = CubicSpline(s, P)
    scale = max(1.0, float(np.max(np.abs(scipys.c))))
    np.testing.assert_allclose(c, scipys.c, rtol=0, atol=1e-9 * scale)
    ours = CubicSpline.construct_fast(c, s)
    np.testing.assert_allclose(ours(s), P, atol=1e-9 * scale)  # it interpolates
    ref_lo, ref_hi = piece_extrema(ours)
    np.testing.assert_allclose(lo, ref_lo, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(hi, ref_hi, rtol=0, atol=1e-12 * scale)


@needs_core
def test_compiled_cubic_path_refuses_bad_knots_and_rows():
    P = np.zeros((3, 2))
    for s, rows in ((np.array([0.0, 1.0, 1.0]), P), (np.array([0.0, np.nan, 2.0]), P), (np.array([0.0]), P[:1]),
                    (np.array([0.0, 1.0, 2.0]), np.full((3, 2), np.inf)), (np.array([0.0, 1.0]), P)):
        with pytest.raises(ValueError):
            CORE.cubic_path(s, rows)


def test_joint_path_fits_the_same_spline_with_or_without_the_core(monkeypatch):
    """:func:`joint_path` (the compiled fit where built) and the numpy fit give the same spline
    through Panda-like waypoints, refinements included (a waypoint near a limit)."""
    from drake_mh.trajectories import paths

    class Robot:
        nq = 3
        lower, upper = np.full(3, -1.0), np.full(3, 1.0)
        continuous = np.zeros(3, dtype=bool)
        name, joint_names = "toy", ("a", "b", "c")

    W = np.array([[0.0, 0.0, 0.0], [0.9, 0.1, 0.0], [0.99, 0.9, 0.0], [0.2, 0.95, 0.0]])
    fitted, s_way = paths._fit(W, Robot, "test", "not-a-knot", 8)
    monkeypatch.setenv("DRAKE_MH_COMPILED_CORE", "0")
    reference, s_ref = paths._fit(W, Robot, "test", "not-a-knot", 8)
    np.testing.assert_allclose(fitted.x, reference.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fitted.c, reference.c, rtol=0, atol=1e-9)
    np.testing.assert_allclose(s_way, s_ref, rtol=0, atol=1e-12)
    assert len(fitted.x) > len(W)  # a piece left the limits and was refined
