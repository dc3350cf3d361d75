"""The compiled ask/tell kernels equal straightforward numpy references on the same draws.

Each optimizer's step kernel is fed a random state (some moves leave the box) and the
uniform / normal draws its ``_ask`` would pass; the reference is the module docstring's
equations written with numpy (or a plain loop where the operator is sequential).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_mh.optim import e3gsa, gsa
from drake_mh.optim._population_kernels import distinct_indices, greedy_replace

P, D = 13, 5
LOWER = np.array([-2.0, -1.0, 0.0, -5.0, 1.0])
UPPER = np.array([3.0, 1.0, 4.0, 5.0, 1.5])
WIDTH = UPPER - LOWER


def state(seed, spread=1.0):
    """Population inside the box, values with ties, a best point and a velocity."""
    rng = np.random.default_rng(seed)
    X = LOWER + rng.random((P, D)) * WIDTH
    F = np.round(rng.random(P) * 5.0)               # ties on purpose
    g = X[int(np.argmin(F))].copy()
    V = (rng.random((P, D)) - 0.5) * WIDTH * spread
    return rng, X, F, g, V


def inside(X):
    return np.all(X >= LOWER) and np.all(X <= UPPER)


# --- shared kernels -------------------------------------------------------------------------


def distinct_reference(U, pool, exclude_self):
    out = np.empty(U.shape, dtype=np.int64)
    for i, row in enumerate(U):
        allowed = [j for j in range(pool) if not (exclude_self and j == i)]
        for m, u in enumerate(row):
            out[i, m] = allowed.pop(int(u * len(allowed)))
    return out


@settings(max_examples=50, deadline=None)
@given(n=st.integers(1, 30), k=st.integers(1, 4), extra=st.integers(0, 10), own=st.booleans(),
       seed=st.integers(0, 10**6))
def test_distinct_indices_is_sequential_sampling_without_replacement(n, k, extra, own, seed):
    pool = max(n if own else 1, k + own) + extra
    U = np.random.default_rng(seed).random((n, k))
    r = distinct_indices(U, pool, own)
    assert np.array_equal(r, distinct_reference(U, pool, own))
    assert all(len(set(row)) == k for row in r) and r.min() >= 0 and r.max() < pool
    if own:
        assert not np.any(r == np.arange(n)[:, None])


def test_distinct_indices_are_uniform():
    U = np.random.default_rng(0).random((40000, 2))
    r = distinct_indices(U, 5, False)
    counts = np.bincount(r[:, 0] * 5 + r[:, 1], minlength=25).reshape(5, 5)
    assert np.all(np.diag(counts) == 0)
    off = counts[~np.eye(5, dtype=bool)]                 # 20 ordered pairs, 2000 expected each
    assert np.all(np.abs(off - 2000) < 5 * math.sqrt(2000))


@pytest.mark.parametrize("ties", [False, True])
def test_greedy_replace(ties):
    _, X, F, _, _ = state(1)
    rng = np.random.default_rng(2)
    Xn, Fn = rng.random((P, D)), F.copy()
    Fn[::3] -= 1.0                                        # better
    Fn[1::3] += 1.0                                       # worse, the rest ties
    better = Fn <= F if ties else Fn < F
    Xr, Fr = np.where(better[:, None], Xn, X), np.where(better, Fn, F)
    assert greedy_replace(X, F, Xn, Fn, ties) == better.sum()
    assert np.array_equal(X, Xr) and np.array_equal(F, Fr)


# --- one test per optimizer ---------------------------------------------------------------


def gsa_acceleration_reference(X, F, W, G):
    """Eqs. (7)-(10) with numpy broadcasting; W (k, N)."""
    k = W.shape[0]
    M = gsa.masses(F)
    att = np.argsort(F, kind="stable")[:k] if k < P else np.arange(P)
    diff = X[att][:, None, :] - X[None, :, :]                     # (k, N, D): x_j - x_i
    w = W * G * M[att][:, None] / (np.linalg.norm(diff, axis=2) + np.finfo(float).eps)
    w[att[:, None] == np.arange(P)[None, :]] = 0.0                 # no self-force
    return np.einsum("kn,knd->nd", w, diff)


def test_gsa_masses_match_the_equations():
    F = np.array([3.0, 1.0, np.inf, 2.0, 1.0])
    fin = F[np.isfinite(F)]
    m = np.where(np.isfinite(F), (F - fin.max()) / (fin.min() - fin.max()), 0.0)
    np.testing.assert_allclose(gsa.masses(F), m / m.sum())


@pytest.mark.parametrize("k", [P, 6, 1])
def test_gsa_acceleration_and_move(k):
    rng, X, F, _, V = state(11, spread=3.0)
    W = rng.random((k, P))
    a = gsa._acceleration_kernel(X, F, W, 7.0, np.finfo(float).eps)
    np.testing.assert_allclose(a, gsa_acceleration_reference(X, F, W, 7.0), rtol=1e-10, atol=1e-12)
    U = rng.random((2, P, D))
    Vr = U[0] * V + a                                                    # (11)
    Xr = X + Vr                                                          # (12)
    out = (Xr < LOWER) | (Xr > UPPER)
    assert out.any()
    Xr = np.where(out, LOWER + U[1] * WIDTH, Xr)
    Xn = gsa._move(X, V, F, W, U, 7.0, np.finfo(float).eps, LOWER, UPPER)
    np.testing.assert_allclose(Xn, Xr, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(V, Vr, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("n_jump", [0, 3, P])
def test_e3gsa_move(n_jump):
    rng, X, F, g, V = state(12)
    a = rng.normal(size=(P, D))
    R = rng.random((4, P, D))
    donors = distinct_indices(rng.random((n_jump, 3)), P, False)
    Vr = R[0] * V + 0.5 * R[1] * a + 1.5 * R[2] * (g - X)
    Xr = X + Vr
    worst = np.argsort(F, kind="stable")[P - n_jump:]
    Xr[worst] = X[donors[:, 0]] + 0.5 * (X[donors[:, 1]] - X[donors[:, 2]])
    Vr[worst] = 0.0
    out = (Xr < LOWER) | (Xr > UPPER)
    Xr = np.where(out, LOWER + R[3] * WIDTH, Xr)
    Xn = e3gsa._move(X, V, F, a, g, R, donors, 0.5, 1.5, 0.5, LOWER, UPPER)
    np.testing.assert_allclose(Xn, Xr, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(V, Vr, rtol=1e-12, atol=1e-12)
    assert inside(Xn)
