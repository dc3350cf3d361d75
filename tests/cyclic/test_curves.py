"""Periodic curves: periods, velocities, user curves."""

from __future__ import annotations

import numpy as np
import pytest

from drake_mh.cyclic.curves import Circle, FunctionCurve, Lissajous, MapleLeaf, SampledCurve, as_curve
from drake_mh.errors import InvalidArgument


@pytest.mark.parametrize("curve", [Lissajous(0.12, 2, 0.4, 0.12, 1, 0.3, phy=0.5), Circle((-0.25, 0.3), 0.3, 3.0),
                                   MapleLeaf(), MapleLeaf(period=3.0)])
def test_periodic_and_velocity(curve):
    t = np.linspace(0, curve.period, 101)
    assert np.allclose(curve.position(t + curve.period), curve.position(t), atol=1e-12)
    numeric = PeriodicCurveFD(curve).velocity(t)
    assert np.allclose(curve.velocity(t), numeric, atol=1e-6 * max(1.0, np.abs(numeric).max()))


class PeriodicCurveFD(FunctionCurve):
    def __init__(self, curve):
        super().__init__(curve.position, curve.period)


def test_maple_leaf_paper_geometry():
    p = MapleLeaf().position(np.array([np.pi / 2]))  # top of the leaf: ρ = 0.1·2·(1+0.3)(1+0.1)
    assert np.allclose(p, [[1.8, 0.5 + 0.286]])


def test_user_curves():
    leaf = MapleLeaf()
    t, p = leaf.sample(2000)
    sampled = SampledCurve(p[:-1], leaf.period)
    tt = np.linspace(0, 10, 333)
    assert np.max(np.abs(sampled.position(tt) - leaf.position(tt))) < 2e-4
    fn = as_curve(lambda t: np.stack([np.cos(t), np.sin(t)], -1), period=2 * np.pi)
    assert np.allclose(fn.velocity(np.array([0.0])), [[0.0, 1.0]], atol=1e-8)
    with pytest.raises(InvalidArgument, match="not periodic"):
        FunctionCurve(lambda t: np.stack([t, t], -1), period=1.0)
    with pytest.raises(InvalidArgument, match="period"):
        as_curve(lambda t: t)
    with pytest.raises(InvalidArgument, match="integer"):
        Lissajous(0.1, 1.5, 0, 0.1, 1, 0)
