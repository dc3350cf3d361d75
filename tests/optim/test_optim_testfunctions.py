"""Benchmark functions: optimum values, shift/rotation, CEC 2017 definitions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.optim.testfunctions import (
    BASE_FUNCTIONS,
    CEC2017_FUNCTIONS,
    cec2017,
    make,
    random_rotation,
)


@pytest.mark.parametrize("name", sorted(BASE_FUNCTIONS))
@pytest.mark.parametrize("rotate", [False, True])
def test_optimum_is_at_the_shift(name, rotate):
    f = make(name, 6, rotate=rotate, seed=1, f_opt=5.0)
    assert f(f.x_opt)[0] == pytest.approx(5.0, abs=1e-9)
    rng = np.random.default_rng(0)
    X = f.lower + rng.random((200, 6)) * (f.upper - f.lower)
    assert np.all(f(X) >= 5.0 - 1e-9)
    assert f(X).shape == (200,)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10**6), dim=st.integers(2, 12), lo=st.floats(-50, 0), w=st.floats(0.5, 100))
def test_random_shift_is_away_from_centre(seed, dim, lo, w):
    f = make("sphere", dim, seed=seed, lower=lo, upper=lo + w)
    c, h = lo + w / 2, w / 2
    off = np.abs(f.x_opt - c) / h
    assert np.all(off >= 0.3 - 1e-12) and np.all(off <= 0.8 + 1e-12)


def test_unshifted_optimum_is_the_origin_and_names_tell():
    f = make("rastrigin", 4, shift="none")
    assert np.array_equal(f.x_opt, np.zeros(4)) and f.name == "rastrigin"
    assert make("rastrigin", 4, rotate=True).name == "shifted_rotated_rastrigin"


def test_rotation_is_orthogonal():
    M = random_rotation(9, np.random.default_rng(2))
    assert np.allclose(M @ M.T, np.eye(9), atol=1e-12)


def test_box_scaling_keeps_the_landscape():
    # the same function on [-5, 5] is the [-100, 100] one with x scaled by 20
    a = make("rastrigin", 3, shift=np.array([1.0, -2.0, 0.5]), lower=-5, upper=5)
    b = make("rastrigin", 3, shift=np.array([20.0, -40.0, 10.0]))
    X = np.random.default_rng(1).uniform(-5, 5, (10, 3))
    assert np.allclose(a(X), b(20 * X))


def test_errors():
    with pytest.raises(UnknownMethod, match="sphere"):
        make("nope", 3)
    with pytest.raises(InvalidArgument):
        make("sphere", 1)
    with pytest.raises(InvalidArgument):
        make("sphere", 3, shift=np.array([0.0, 500.0, 0.0]))
    with pytest.raises(UnknownMethod):
        cec2017(2, 10)
    with pytest.raises(InvalidArgument):
        cec2017(1, 10, data="nope")


# --- CEC 2017: independent scalar transcriptions of the report's definitions -----------------


def _z(f, x):
    return f.rotation @ (f.scale * (x - f.shift))


def ref_zakharov(z):
    s1 = sum(zi * zi for zi in z)
    s2 = sum(0.5 * (i + 1) * zi for i, zi in enumerate(z))
    return s1 + s2 ** 2 + s2 ** 4


def ref_rastrigin(z):
    return sum(zi * zi - 10.0 * math.cos(2 * math.pi * zi) + 10.0 for zi in z)


def ref_levy(z):
    w = [1.0 + zi / 4.0 for zi in z]
    total = math.sin(math.pi * w[0]) ** 2
    for wi in w[:-1]:
        total += (wi - 1) ** 2 * (1 + 10 * math.sin(math.pi * wi + 1) ** 2)
    return total + (w[-1] - 1) ** 2 * (1 + math.sin(2 * math.pi * w[-1]) ** 2)


@pytest.mark.parametrize("number, ref", [(3, ref_zakharov), (5, ref_rastrigin), (9, ref_levy)])
@pytest.mark.parametrize("data", ["generated", "auto"])
def test_cec2017_matches_scalar_definition(number, ref, data):
    f = cec2017(number, 10, data=data)
    X = np.random.default_rng(number).uniform(-100, 100, (8, 10))
    expected = [ref(_z(f, x)) + 100.0 * number for x in X]
    assert np.allclose(f(X), expected, rtol=1e-12)
    assert f(f.x_opt)[0] == pytest.approx(f.f_opt, abs=1e-8)


@pytest.mark.parametrize("number", sorted(CEC2017_FUNCTIONS))
def test_cec2017_generated_data_is_seeded(number):
    a, b = cec2017(number, 10, data="generated", seed=1), cec2017(number, 10, data="generated", seed=1)
    assert np.array_equal(a.shift, b.shift) and np.array_equal(a.rotation, b.rotation)
    assert np.all(np.abs(a.shift) <= 80)


@pytest.mark.parametrize("dim", [10, 30])
def test_cec2017_official_data_matches_opfunu_where_opfunu_is_correct(dim):
    """F1, F4 and F10 of opfunu 1.0.4 agree with the report once given the right data files."""
    oc = pytest.importorskip("opfunu.cec_based.cec2017")
    refs = {
        1: oc.F12017(ndim=dim),
        4: oc.F32017(ndim=dim, f_shift="shift_data_4", f_matrix="M_4_D", f_bias=400.0),
        10: oc.F92017(ndim=dim, f_shift="shift_data_10", f_matrix="M_10_D", f_bias=1000.0),
    }
    X = np.random.default_rng(dim).uniform(-100, 100, (6, dim))
    for number, ref in refs.items():
        f = cec2017(number, dim, data="official")
        assert np.allclose(f(X), [ref.evaluate(x) for x in X], rtol=1e-12), number
        assert np.allclose(f.shift, ref.f_shift)
