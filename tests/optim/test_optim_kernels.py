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

from drake_mh.optim import abc, ao, aro, bat, de, e3gsa, ga, gsa, pso, woa
from drake_mh.optim.population import distinct_indices, greedy_replace

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


@pytest.mark.parametrize("seed", range(4))
def test_pso_step(seed):
    rng, X, _, g, V = state(seed, spread=2.0)
    Pb = LOWER + rng.random((P, D)) * WIDTH
    R = rng.random((2, P, D))
    w, c1, c2, vmax = 0.7, 2.0, 2.0, 0.6 * WIDTH
    Vr = np.clip(w * V + c1 * R[0] * (Pb - X) + c2 * R[1] * (g - X), -vmax, vmax)
    Xr = X + Vr
    out = (Xr < LOWER) | (Xr > UPPER)
    Xr, Vr[out] = np.clip(Xr, LOWER, UPPER), 0.0
    assert out.any()
    Xn = pso._step(X, V, Pb, g, R, w, c1, c2, vmax, LOWER, UPPER)
    np.testing.assert_allclose(Xn, Xr, rtol=0, atol=1e-12)
    np.testing.assert_allclose(V, Vr, rtol=0, atol=1e-12)


@pytest.mark.parametrize("per_dim", [True, False])
def test_bat_move_and_accept(per_dim):
    rng, X, F, g, V = state(3)
    r, A = rng.random(P), 1.0 + rng.random(P)
    R = rng.random((P, D + 2 + (D if per_dim else 1)))
    freq = 0.0 + 2.0 * R[:, D + 2:]
    Vr = np.clip(V + (X - g) * freq, -WIDTH, WIDTH)
    Xr = X + Vr
    local = R[:, D] > r
    assert local.any() and not local.all()
    Xr[local] = g + (2.0 * R[local, :D] - 1.0) * (0.01 * A.mean()) * WIDTH
    Xr = np.clip(Xr, LOWER, UPPER)
    Xn = bat._move(X, V, g, R, 0.0, 2.0, r, A, 0.01, LOWER, UPPER, WIDTH)
    np.testing.assert_allclose(Xn, Xr, rtol=0, atol=1e-12)
    np.testing.assert_allclose(V, Vr, rtol=0, atol=1e-12)
    # eq. (6)
    Fn = F + rng.normal(size=P)
    r0, draw = rng.random(P), R[:, D + 1]
    acc = (Fn < F) & (draw < A)
    Xa, Fa = np.where(acc[:, None], Xn, X), np.where(acc, Fn, F)
    Aa, ra = np.where(acc, 0.9 * A, A), np.where(acc, r0 * 0.5, r)
    bat._accept(X, F, Xn, Fn, draw, A, r, r0, 0.9, 0.5)
    assert acc.any()
    assert np.array_equal(X, Xa) and np.array_equal(F, Fa) and np.allclose(A, Aa) and np.allclose(r, ra)


@pytest.mark.parametrize("a", [1.8, 0.4])
def test_woa_move(a):
    rng, X, _, g, _ = state(4)
    R = rng.random((P, 5))
    A, C = (2.0 * a * R[:, 0] - a)[:, None], (2.0 * R[:, 1])[:, None]
    l = (2.0 * R[:, 3] - 1.0)[:, None]
    ref = np.where(np.abs(A) < 1.0, g, X[(R[:, 4] * P).astype(int)])
    enc = ref - A * np.abs(C * ref - X)                                      # (2.1), (2.7)
    spiral = np.abs(g - X) * np.exp(l) * np.cos(2.0 * np.pi * l) + g         # (2.5)
    Xr = np.clip(np.where((R[:, 2] < 0.5)[:, None], enc, spiral), LOWER, UPPER)
    np.testing.assert_allclose(woa._move(X, g, R, a, 1.0, LOWER, UPPER), Xr, rtol=0, atol=1e-12)


@pytest.mark.parametrize("a", [1.8, 0.4])
def test_woa_greedy_move(a):
    """mealpy 3.0.3's OriginalWOA move: one r for A and C, a uniform box point for |A| >= 1."""
    rng, X, _, g, _ = state(4)
    R = rng.random((P, 3 + D))
    r = R[:, 0:1]
    A, C = 2.0 * a * r - a, 2.0 * r
    l = 2.0 * R[:, 2:3] - 1.0
    box = LOWER + R[:, 3:] * WIDTH
    ref = np.where(np.abs(A) < 1.0, g, box)
    enc = ref - A * np.abs(C * ref - X)
    spiral = g + np.exp(l) * np.cos(2.0 * np.pi * l) * np.abs(g - X)
    explore = (R[:, 1] < 0.5) & (np.abs(A[:, 0]) >= 1.0)
    assert explore.any() == (a > 1.0) and (R[:, 1] >= 0.5).any()
    Xr = np.clip(np.where((R[:, 1] < 0.5)[:, None], enc, spiral), LOWER, UPPER)
    np.testing.assert_allclose(woa._move_greedy(X, g, R, a, 1.0, LOWER, UPPER), Xr, rtol=0, atol=1e-12)


def test_woa_greedy_keeps_a_whale_unless_strictly_better():
    opt = woa.WOAGreedy((LOWER, UPPER), budget=20 * P, seed=3, pop_size=P)
    sphere = lambda Z: np.round(np.sum((Z - 0.5) ** 2, axis=1))    # rounded: ties happen
    X = opt.ask()
    opt.tell(X, sphere(X))
    while not opt.done:
        X0, F0 = opt.X.copy(), opt.F.copy()
        Xn = opt.ask()
        Fn = sphere(Xn)
        opt.tell(Xn, Fn)
        moved = Fn < F0
        assert np.array_equal(opt.X, np.where(moved[:, None], Xn, X0))
        assert np.array_equal(opt.F, np.where(moved, Fn, F0))


@pytest.mark.parametrize("t, early", [(3, True), (25, False)])
def test_ao_move(t, early):
    rng, X, _, g, _ = state(5)
    T, c = 30, ao.AOConfig()
    R = rng.random((P, 5))
    levy_rows = R[:, 0] > 0.5
    n = int(levy_rows.sum())
    Z = rng.standard_normal((2, n, D))
    B = np.empty((0, D)) if early else rng.random((P - n, D))
    sigma = ao.levy_sigma(c.beta)
    L = np.zeros((P, D))
    L[levy_rows] = c.s * Z[0] * sigma / np.abs(Z[1]) ** (1.0 / c.beta)      # (6)-(7), in order
    D1 = np.arange(1, D + 1)
    rad, theta = c.r1 + c.U * D1, -c.omega * D1 + 1.5 * np.pi
    spiral = rad * np.cos(theta) - rad * np.sin(theta)
    tau, XM, r = t / T, X.mean(axis=0), R[:, 1:2]
    if early:
        X1 = g * (1.0 - tau) + (XM - g * r)                                  # (3)
        X2 = g * L + X[(R[:, 4] * P).astype(int)] + spiral * r               # (5)
        Xr = np.where(levy_rows[:, None], X2, X1)
    else:
        box = np.zeros((P, D))
        box[~levy_rows] = LOWER + WIDTH * B
        X3 = (g - XM) * c.alpha - r + box * c.delta                          # (13)
        QF = float(t) ** ((2.0 * R[:, 2:3] - 1.0) / (1.0 - T) ** 2)
        G1 = 2.0 * R[:, 3:4] - 1.0
        X4 = QF * g - G1 * X * r - 2.0 * (1.0 - tau) * L + r * G1           # (14)
        Xr = np.where(levy_rows[:, None], X4, X3)
    Xr = np.clip(Xr, LOWER, UPPER)
    Xn = ao._move(X, g, R, Z, B, t, T, early, c.alpha, c.delta, c.s * sigma, 1.0 / c.beta, spiral,
                  LOWER, UPPER)
    np.testing.assert_allclose(Xn, Xr, rtol=1e-12, atol=1e-12)


def test_de_trial():
    rng, X, _, _, _ = state(6)
    U = rng.random((P, D + 4))
    U[:, 4:] = np.where(rng.random((P, D)) < 0.3, 0.95, U[:, 4:])           # some CR failures
    r = distinct_indices(U[:, :3], P, True)
    V = X[r[:, 0]] + 1.7 * (X[r[:, 1]] - X[r[:, 2]])                          # (4), big F: leaves the box
    cross = U[:, 4:] <= 0.9
    cross[np.arange(P), (U[:, 3] * D).astype(int)] = True                    # (5)
    Ur = np.where(cross, V, X)
    assert ((Ur < LOWER) | (Ur > UPPER)).any() and not cross.all()
    Ur = np.where(Ur < LOWER, 0.5 * (X + LOWER), Ur)
    Ur = np.where(Ur > UPPER, 0.5 * (X + UPPER), Ur)
    Xt = de._trial(X, r, U, 1.7, 0.9, LOWER, UPPER)
    np.testing.assert_allclose(Xt, Ur, rtol=0, atol=1e-12)
    assert inside(Xt)


def aro_reference(X, U, N, t, T, amnn):
    """Per-rabbit loop over the module docstring's equations."""
    Xr = np.empty_like(X)
    for i in range(P):
        u = U[i]
        A = 4.0 * (1.0 - t / T) * math.log(1.0 / u[0])
        n_dims = math.ceil(u[1] * D)
        perm = list(range(D))                                 # partial Fisher-Yates
        for m in range(n_dims):
            q = m + int(u[8 + m] * (D - m))
            perm[m], perm[q] = perm[q], perm[m]
        c = np.zeros(D)
        c[perm[:n_dims]] = 1.0
        R = (math.e - math.exp(((t - 1) / T) ** 2)) * math.sin(2.0 * math.pi * u[2]) * c
        j = (i + 1 + int(u[6] * (P - 1))) % P
        if A > 1.0:
            if amnn:
                v = X[i] + R * (X[j] - X[i])
            else:
                v = X[j] + R * (X[i] - X[j]) + round(0.5 * (0.05 + u[3])) * N[0, i]
        else:
            g = np.zeros(D)
            g[int(u[7] * D)] = 1.0
            H = (T - t + 1) / T * (u[4] if amnn else N[1, i])
            b = X[i] + H * g * X[i]
            v = X[i] + R * (u[5] * b - X[i])
        out = (v < LOWER) | (v > UPPER)
        if amnn:
            v = np.clip(v, LOWER, UPPER)
        else:
            v = np.where(out, LOWER + U[i, 8 + D:] * WIDTH, v)
        Xr[i] = v
    return Xr


@pytest.mark.parametrize("amnn", [False, True])
@pytest.mark.parametrize("t", [1, 20, 29])
def test_aro_move(amnn, t):
    rng, X, _, _, _ = state(7 + t)
    X *= 3.0                                                   # hiding and jumps leave the box
    X = np.clip(X, LOWER, UPPER)
    U = rng.random((P, 8 + (D if amnn else 2 * D)))
    N = np.empty((2, 0)) if amnn else rng.standard_normal((2, P)) * 3.0
    Xn = aro.rabbit_moves(X, U, N, t, 30, amnn, LOWER, UPPER)
    np.testing.assert_allclose(Xn, aro_reference(X, U, N, t, 30, amnn), rtol=1e-12, atol=1e-12)
    assert inside(Xn)


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


def ga_reference(X, n_keep, p_rank, U, blend, reset, rate, eta_c=15.0, eta_m=20.0):
    N = len(X)
    pairs = math.ceil((N - n_keep) / 2)
    u, U = U[: 2 * pairs], U[2 * pairs:]
    c = np.cumsum(p_rank)
    par = np.minimum(np.searchsorted(c, u * c[-1], side="right"), n_keep - 1)
    M, Dd = X[par[:pairs]], X[par[pairs:]]
    if blend:
        a, b, U = (U[:pairs] * D).astype(int), U[pairs:2 * pairs], U[2 * pairs:]
        right = np.arange(D)[None, :] > a[:, None]
        C1, C2 = np.where(right, Dd, M), np.where(right, M, Dd)
        rows = np.arange(pairs)
        ma, da = M[rows, a], Dd[rows, a]
        C1[rows, a], C2[rows, a] = ma - b * (ma - da), da + b * (ma - da)
    else:
        us, sw, U = U[:pairs * D].reshape(pairs, D), U[pairs * D:2 * pairs * D].reshape(pairs, D), U[2 * pairs * D:]
        e = 1.0 / (eta_c + 1.0)
        beta = np.where(us <= 0.5, (2.0 * us) ** e, (0.5 / (1.0 - us)) ** e)
        beta = np.where(sw < 0.5, beta, 1.0)
        C1 = np.clip(0.5 * ((1 + beta) * M + (1 - beta) * Dd), LOWER, UPPER)
        C2 = np.clip(0.5 * ((1 - beta) * M + (1 + beta) * Dd), LOWER, UPPER)
    Y = np.concatenate([X[:n_keep], np.concatenate([C1, C2])[: N - n_keep]])
    mask = U[: (N - 1) * D].reshape(N - 1, D) < rate
    v = U[(N - 1) * D:].reshape(N - 1, D)
    if reset:
        R = LOWER + v * WIDTH
    else:
        e = 1.0 / (eta_m + 1.0)
        delta = np.where(v < 0.5, (2.0 * v) ** e - 1.0, 1.0 - (2.0 * (1.0 - v)) ** e)
        R = np.clip(Y[1:] + delta * WIDTH, LOWER, UPPER)
    Y[1:] = np.where(mask, R, Y[1:])
    changed = np.zeros(N, dtype=bool)
    changed[n_keep:] = True
    changed[1:] |= mask.any(axis=1)
    return Y, np.flatnonzero(changed)


@pytest.mark.parametrize("blend, reset", [(True, True), (False, False), (True, False), (False, True)])
@pytest.mark.parametrize("n_keep", [7, 6])          # odd and even number of children
def test_ga_offspring_and_survivors(blend, reset, n_keep):
    rng, X, F, _, _ = state(13)
    order = np.argsort(F, kind="stable")
    X, F = X[order], F[order]
    ranks = np.arange(n_keep, 0, -1, dtype=float)
    p_rank = ranks / ranks.sum()
    pairs = math.ceil((P - n_keep) / 2)
    U = rng.random(2 * pairs + (2 * pairs if blend else 2 * pairs * D) + 2 * (P - 1) * D)
    Y, changed = ga._offspring(X, n_keep, np.cumsum(p_rank), U, blend, reset, 0.1, 15.0, 20.0, LOWER, UPPER)
    Yr, cr = ga_reference(X, n_keep, p_rank, U, blend, reset, 0.1)
    np.testing.assert_allclose(Y, Yr, rtol=1e-12, atol=1e-12)
    assert np.array_equal(changed, cr) and inside(Y) and np.array_equal(Y[0], X[0])
    Fc = rng.random(len(changed))
    FY = F.copy()
    FY[changed] = Fc
    o = np.argsort(FY, kind="stable")
    Xs, Fs = ga._sorted(Y, F, changed, Fc)
    assert np.array_equal(Xs, Y[o]) and np.array_equal(Fs, FY[o])


def test_abc_roulette_uses_karaboga_fitness():
    rng = np.random.default_rng(14)
    for F in (rng.random(9) * 10, rng.normal(size=9) * 10):
        u = rng.random(500)
        c = np.cumsum(abc.abc_fitness(F))
        ref = np.minimum(np.searchsorted(c, u * c[-1], side="right"), len(F) - 1)
        assert np.array_equal(abc._roulette_kernel(F, u), ref)
