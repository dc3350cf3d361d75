"""Trapezoidal Cartesian paths (framework paper §3.3, Table 3)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_mh.errors import InvalidArgument
from drake_mh.paths import TABLE3_POINTS, TrapezoidalProfile, trapezoidal_path


def test_table3_path_is_a_closed_loop_of_50_points_through_every_stop():
    path = trapezoidal_path()  # Table 3: start/end (0.2, 0.8, 0.3), via (1.0, 0.2, 0.2), (0.5, 0.4, 0.1)
    assert len(path) == 50 and path.points.shape == (50, 3)
    assert np.allclose(path.points[path.stop_indices], np.array(TABLE3_POINTS), atol=1e-12)
    assert np.allclose(path.points[0], path.points[-1])  # start = end
    assert np.all(np.diff(path.times) > 0) and path.times[0] == 0.0
    assert np.allclose(path.speeds[path.stop_indices], 0.0)  # the tool stops at every given point
    assert path.length == pytest.approx(sum(np.linalg.norm(np.diff(np.array(TABLE3_POINTS), axis=0), axis=1)))


@settings(max_examples=40, deadline=None)
@given(k=st.integers(2, 6), n_extra=st.integers(0, 120), seed=st.integers(0, 10_000),
       v=st.floats(0.05, 2.0), a=st.floats(0.05, 5.0))
def test_path_properties(k, n_extra, seed, v, a):
    rng = np.random.default_rng(seed)
    P = rng.uniform(-1, 1, (k, 3))
    profile = TrapezoidalProfile(v, a)
    n = k + n_extra
    path = trapezoidal_path(P, n, profile)
    assert len(path) == n  # N points in all
    assert np.array_equal(path.points[path.stop_indices], P)  # passes through every given point, in order
    assert np.all(np.diff(path.stop_indices) >= 1)
    assert np.all(np.diff(path.times) > 0)  # monotone timing
    assert np.all(path.speeds <= v + 1e-12)
    # every point lies on its segment, and the distance travelled matches the speed profile
    for i in range(k - 1):
        idx = np.flatnonzero(path.segment == i)
        u = (P[i + 1] - P[i]) / np.linalg.norm(P[i + 1] - P[i])
        d = path.points[idx] - P[i]
        along = d @ u
        assert np.allclose(d, np.outer(along, u), atol=1e-9)
        assert np.all(np.diff(along) > 0) and along[0] >= 0  # forward only
    assert path.duration == pytest.approx(sum(profile.duration(L) for L in np.linalg.norm(np.diff(P, axis=0), axis=1)))


def test_trapezoid_and_triangle_profiles():
    prof = TrapezoidalProfile(v_max=1.0, a_max=2.0)
    # long segment: accelerate 0.5 s (0.25 m), cruise, decelerate 0.5 s
    L = 3.0
    T = prof.duration(L)
    assert T == pytest.approx(3.0 / 1.0 + 0.5)
    t = np.linspace(0, T, 1001)
    s, sd = prof.distance(t, L), prof.speed(t, L)
    assert s[0] == 0 and s[-1] == pytest.approx(L) and np.all(np.diff(s) >= 0)
    assert sd.max() == pytest.approx(1.0) and np.all(np.abs(np.diff(sd) / np.diff(t)) <= 2.0 + 1e-9)
    assert prof.distance(0.5, L) == pytest.approx(0.25)
    # finite differences of s give the speed
    assert np.allclose(np.gradient(s, t)[1:-1], sd[1:-1], atol=5e-3)
    # short segment: triangle, peak sqrt(L a) < v_max
    Ls = 0.1
    assert prof.duration(Ls) == pytest.approx(2 * np.sqrt(Ls / 2.0))
    assert prof.speed(prof.duration(Ls) / 2, Ls) == pytest.approx(np.sqrt(Ls * 2.0))


def test_points_are_denser_where_the_tool_is_slow():
    path = trapezoidal_path([[0, 0, 0], [2, 0, 0]], 41, TrapezoidalProfile(0.5, 0.25))
    gaps = np.diff(path.points[:, 0])
    assert gaps[0] < gaps[len(gaps) // 2] and gaps[-1] < gaps[len(gaps) // 2]


def test_bad_input():
    with pytest.raises(InvalidArgument, match="shape"):
        trapezoidal_path([[0, 0], [1, 1]])
    with pytest.raises(InvalidArgument, match="n_points"):
        trapezoidal_path(TABLE3_POINTS, 3)
    with pytest.raises(InvalidArgument, match="equal"):
        trapezoidal_path([[0, 0, 0], [0, 0, 0], [1, 0, 0]])
    with pytest.raises(InvalidArgument, match="v_max"):
        TrapezoidalProfile(v_max=0.0)
