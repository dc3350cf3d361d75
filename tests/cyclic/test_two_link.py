"""Eq. (16) polynomials and the staged, cyclic 2-link trajectory (eq. (25))."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.two_link import StagedPolynomial, sixth_order_coefficients
from drake_mh.errors import InvalidArgument


@pytest.mark.parametrize("a6", [0.0, 10.0, -3.5])
def test_eq16_boundary_conditions(a6):
    a0, a3, a4, a5, a6_ = sixth_order_coefficients(-2.75, -2.6, a6)
    poly = np.polynomial.Polynomial([a0, 0, 0, a3, a4, a5, a6_])
    assert poly(0) == pytest.approx(-2.75, abs=1e-14) and poly(1) == pytest.approx(-2.6, abs=1e-13)
    for d in (1, 2):
        assert abs(poly.deriv(d)(0)) < 1e-12 and abs(poly.deriv(d)(1)) < 1e-12
    if a6 == 0:  # minimum-jerk quintic
        assert np.allclose([a3, a4, a5], np.array([10, -15, 6]) * 0.15)


def test_staged_polynomial_is_cyclic_and_smooth():
    knots = np.array([[-2.75, 1.3], [-2.6, 1.8], [-1.8, 1.0], [-2.0, 2.0]])
    traj = StagedPolynomial(knots, period=2 * np.pi, a6=[[1.0, -2.0]] * 4)
    T = traj.period
    t = np.linspace(0, T, 2001)
    q = traj.q(t)
    assert np.allclose(q[0], knots[0]) and np.allclose(q[-1], knots[0])
    for c in (1, 7, 500):
        assert np.max(np.abs(traj.q(t[:50] + c * T) - q[:50])) < 1e-9 * c
    # stage boundaries: knots reached, velocities zero, no jumps
    assert np.allclose(traj.q(np.arange(4) * T / 4), knots, atol=1e-12)
    assert np.allclose(traj.qd(np.arange(4) * T / 4), 0.0, atol=1e-12)
    assert np.max(np.abs(np.diff(q, axis=0))) < 0.02
    # qd is the derivative of q
    h = 1e-6
    assert np.allclose(traj.qd(t[1:-1]), (traj.q(t[1:-1] + h) - traj.q(t[1:-1] - h)) / (2 * h), atol=1e-6)


def test_staged_polynomial_errors():
    with pytest.raises(InvalidArgument, match="stage_fractions"):
        StagedPolynomial([[0.0, 0.0], [1.0, 1.0]], stage_fractions=[0, 0.7, 0.6])
    with pytest.raises(InvalidArgument, match="knots"):
        StagedPolynomial([0.0, 1.0])
