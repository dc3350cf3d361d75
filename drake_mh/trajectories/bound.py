"""Upper bounds of a trajectory's position, velocity, acceleration and jerk between samples.

Between two consecutive :attr:`~drake_mh.trajectories.trajectory.Trajectory.breaks`, every
joint's ``q(t) = path(s(t))`` is one polynomial: a path piece of degree ``d_p`` composed with a
timing piece of degree ``d_s`` has degree ``d_p · d_s`` (toppra: cubic spline, quadratic timing,
degree 6; Drake's Toppra: cubic timing, degree 9; ruckig and via-point polynomials: the path's
own degree), and its ``k``-th derivative degree ``d_p · d_s - k``. A polynomial of degree ``n``
on a piece lies within the range of its ``n + 1`` Bernstein coefficients (convex-hull property
of the Bernstein basis), so ``max |f| <= max_i |b_i|`` is a *bound*, not a sample.

The coefficients come from the values at ``n + 1`` Chebyshev-Lobatto nodes of the piece (exact
interpolation of a degree-``n`` polynomial; ``b = M v`` with ``M`` the inverse of the Bernstein
basis at the nodes). The bound converges to the maximum as ``O(h²)`` when a piece of length
``h`` is halved, so pieces whose bound exceeds the largest value seen so far by more than
``slack`` are halved, up to ``max_levels`` times; a piece still unsettled then keeps its (valid,
pessimistic) bound. A halving splits the coefficients themselves (de Casteljau at 1/2: convex
combinations, no new evaluation of the trajectory), and the first and last coefficient of each
half are the polynomial's values at its ends, which raise the largest value seen.
"""

from __future__ import annotations

import functools
from math import comb

import numba
import numpy as np

from drake_mh._support.native import compiled_core

__all__ = ["MAX_LEVELS", "ONE_SIDED", "SLACK", "kinematic_bound", "piece_degree", "sample_bound_nodes"]


ONE_SIDED = 1e-9
"""[fraction of a piece] values at a piece's ends are taken this far inside it (its own
polynomial, not the next piece's): :func:`kinematic_bound` interpolates at those fractions, so the
polynomial it bounds is the piece's, exactly."""


SLACK = 1e-8
"""[ratio] :func:`kinematic_bound` halves a piece while its bound exceeds the largest value seen by more."""

MAX_LEVELS = 30
"""Halvings :func:`kinematic_bound` makes at most (a piece still open keeps its valid bound)."""


def piece_degree(trajectory) -> int:
    """Degree of ``q(t)`` on a piece between breaks (see the module docstring)."""
    degree = trajectory.path.c.shape[0] - 1
    if trajectory.timing is not None:
        degree *= trajectory.timing.c.shape[0] - 1
    return int(degree)


@functools.lru_cache(maxsize=64)
def _to_bernstein(u: tuple) -> np.ndarray:
    """``M`` with ``b = M v``: values at the nodes ``u`` (``n + 1`` distinct points of [0, 1]) to
    the Bernstein coefficients of the degree-``n`` polynomial through them."""
    n = len(u) - 1  # Python floats: a handful of numbers, each numpy call would cost more
    basis = [[comb(n, i) * uj**i * (1.0 - uj) ** (n - i) for i in range(n + 1)] for uj in map(float, u)]
    return np.linalg.inv(np.array(basis))


def _sample_nodes(tau: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(pick, M)``: ``n + 1`` of the sample fractions ``tau`` spread over them (indices) and
    ``M`` from the values there (pulled inside by :data:`ONE_SIDED`) to Bernstein coefficients."""
    return _nodes_of(np.ascontiguousarray(tau, dtype=float).tobytes(), n)


@functools.lru_cache(maxsize=64)
def _nodes_of(tau_bytes: bytes, n: int) -> tuple[np.ndarray, np.ndarray]:
    tau = np.frombuffer(tau_bytes, dtype=float).tolist()
    last = len(tau) - 1  # n + 1 indices spread over the samples (numpy's linspace and round, in Python)
    step = last / n if n else 0.0
    pick = sorted({round(k * step) if k < n else last for k in range(n + 1)} if n else {0})
    nodes = tuple(min(max(tau[i], ONE_SIDED), 1.0 - ONE_SIDED) for i in pick)
    return np.array(pick, dtype=np.int64), _to_bernstein(nodes)


@functools.lru_cache(maxsize=16)
def _interpolation(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev-Lobatto nodes ``u (n+1,)`` on [0, 1] and their ``M`` (values -> Bernstein)."""
    if n == 0:
        return np.array([0.5]), np.ones((1, 1))
    u = 0.5 * (1.0 - np.cos(np.pi * np.arange(n + 1) / n))
    return u, _to_bernstein(tuple(u))


@functools.lru_cache(maxsize=16)
def _halves(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(S_L, S_R)``, ``(n+1, n+1)``: the Bernstein coefficients of a degree-``n`` polynomial on
    [0, 1/2] and on [1/2, 1] from those on [0, 1] (de Casteljau at 1/2)."""
    left, right = np.zeros((n + 1, n + 1)), np.zeros((n + 1, n + 1))
    for i in range(n + 1):
        for j in range(i + 1):
            left[i, j] = comb(i, j) / 2.0**i
        for j in range(i, n + 1):
            right[i, j] = comb(n - i, j - i) / 2.0 ** (n - i)
    return left, right


def sample_bound_nodes(tau: np.ndarray, degree: int, orders: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What :func:`kinematic_bound` with ``samples=(tau, ...)`` uses, for the compiled core's
    ``certify_samples`` (``bound_n1``, ``bound_picks``, ``bound_mats``): per order (``-1``: none,
    e.g. torque) the number of nodes ``n + 1`` (``n = max(degree - order, 0)``; 0 where there
    are not more samples than ``n``: the bound then evaluates nodes of its own), their sample
    indices, and ``M, S_L, S_R`` (:func:`_sample_nodes`, :func:`_halves`) flattened, in order.
    Cached per ``(tau, degree, orders)``."""
    return _nodes_spec(np.ascontiguousarray(tau, dtype=float).tobytes(), int(degree), tuple(orders))


@functools.lru_cache(maxsize=64)
def _nodes_spec(tau_bytes: bytes, degree: int, orders: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    tau = np.frombuffer(tau_bytes, dtype=float)
    n1s, picks, mats = [], [], []
    for order in orders:
        n = max(degree - order, 0)
        if order < 0 or len(tau) <= n:
            n1s.append(0)
            continue
        pick, M0 = _sample_nodes(tau, n)
        left, right = _halves(n)
        n1s.append(len(pick))
        picks.append(pick)
        mats += [M0.ravel(), left.ravel(), right.ravel()]
    as_ints = np.concatenate(picks).astype(np.int64) if picks else np.zeros(0, np.int64)
    as_floats = np.concatenate(mats) if mats else np.zeros(0)
    return np.array(n1s, dtype=np.int64), np.ascontiguousarray(as_ints), np.ascontiguousarray(as_floats, dtype=float)


@numba.njit(cache=True, error_model="numpy")  # x / 0 -> inf, as numpy (a joint without range)
def _subdivide(B, V, centre, half, best, slack, max_levels, left, right):
    """The halving loop of :func:`kinematic_bound`, compiled (a level took about 70 µs of numpy
    calls on a handful of pieces): per joint ``j`` the ratio of ``[lo, hi]`` is
    ``max(hi - centre_j, centre_j - lo) / half_j``. ``B (P, n+1, nq)``: Bernstein coefficients,
    ``V (P, m, nq)``: values of the pieces seen so far. Returns the bound ``(nq,)``."""
    nq = B.shape[2]
    best = best.copy()
    certified = np.full(nq, -np.inf)
    for p in range(V.shape[0]):
        for i in range(V.shape[1]):
            for j in range(nq):
                r = max(V[p, i, j] - centre[j], centre[j] - V[p, i, j]) / half[j]
                best[j] = max(best[j], r)
    for level in range(max_levels + 1):
        P, n1 = B.shape[0], B.shape[1]
        if P == 0:
            break
        bound = np.empty((P, nq))
        for p in range(P):
            for j in range(nq):
                lo, hi = B[p, 0, j], B[p, 0, j]
                for i in range(1, n1):
                    lo, hi = min(lo, B[p, i, j]), max(hi, B[p, i, j])
                bound[p, j] = max(hi - centre[j], centre[j] - lo) / half[j]
        keep = np.zeros(P, np.bool_)
        for p in range(P):
            open_ = False
            if level < max_levels:
                for j in range(nq):
                    open_ |= bound[p, j] > best[j] + slack
            if open_:
                keep[p] = True
            else:
                for j in range(nq):
                    certified[j] = max(certified[j], bound[p, j])
        K = np.flatnonzero(keep)
        halves = np.empty((2 * K.shape[0], n1, nq))
        for q in range(K.shape[0]):
            p = K[q]
            for i in range(n1):
                for j in range(nq):
                    acc_l, acc_r = 0.0, 0.0
                    for k in range(n1):
                        acc_l += left[i, k] * B[p, k, j]
                        acc_r += right[i, k] * B[p, k, j]
                    halves[q, i, j] = acc_l
                    halves[K.shape[0] + q, i, j] = acc_r
        for p in range(halves.shape[0]):  # the halves' end values: exact values of the polynomial
            for i in (0, n1 - 1):
                for j in range(nq):
                    best[j] = max(best[j], max(halves[p, i, j] - centre[j], centre[j] - halves[p, i, j]) / half[j])
        B = halves
    for j in range(nq):
        certified[j] = max(certified[j], best[j])
    return certified


def kinematic_bound(trajectory, order: int, ratio: tuple, t0: np.ndarray, t1: np.ndarray, best: np.ndarray,
                    samples=None, slack: float = SLACK, max_levels: int = MAX_LEVELS) -> np.ndarray:
    """Per joint, an upper bound of the ratio of ``q^(order)(t)`` over the pieces ``[t0, t1]``.

    Args:
        trajectory: the :class:`~drake_mh.trajectories.trajectory.Trajectory`.
        order: 0 (position) .. 3 (jerk).
        ratio: ``(centre (nq,), half (nq,))``: a value ``x`` of joint ``j`` has the ratio
            ``|x - centre_j| / half_j`` (a range ``[lo, hi]``: ``max(hi - c, c - lo) / half``;
            symmetric limits ``L``: centre 0, half ``L``; ``inf``: ratio 0).
        t0, t1: ``(P,)`` piece ends [s] (consecutive breaks).
        best: ``(nq,)`` the largest ratio already found by sampling (a lower bound of the
            maximum); pieces are halved until their bound is within ``slack`` of it.
        samples: optional ``(tau (K,), V (P, K, nq))``, values of ``q^(order)`` at
            ``t0 + tau (t1 - t0)`` already computed (certify's samples): the first level then
            interpolates ``n + 1`` of them instead of evaluating the trajectory again.
        slack: ratio units.
        max_levels: halvings at most.

    Returns:
        ``(nq,)`` ratios that no point of the pieces exceeds.
    """
    n = max(piece_degree(trajectory) - order, 0)
    u, M = _interpolation(n)
    left, right = _halves(n)
    best = np.array(best, dtype=float)
    centre, half = (np.ascontiguousarray(np.broadcast_to(np.asarray(x, float), best.shape)) for x in ratio)
    a, b = np.asarray(t0, float), np.asarray(t1, float)
    # the values are taken one-sided (each piece's own polynomial at its ends: pulled inside by
    # ONE_SIDED of the piece, as certify samples), so they interpolate at those fractions
    if samples is not None and len(samples[0]) > n:
        tau, V_all = samples
        pick, M0 = _sample_nodes(tau, n)
        V = V_all[:, pick]
    else:
        h = b - a
        T = np.clip(a[:, None] + u[None, :] * h[:, None], (a + ONE_SIDED * h)[:, None], (b - ONE_SIDED * h)[:, None])
        V = trajectory.derivatives(T.ravel(), order)[order].reshape(len(a), n + 1, -1)  # (P, n+1, nq)
        M0 = _to_bernstein(tuple(np.clip(u, ONE_SIDED, 1.0 - ONE_SIDED))) if n > 0 else M
    B = np.matmul(M0, V)  # (P, n+1, nq) Bernstein coefficients per piece
    arguments = (np.ascontiguousarray(B), np.ascontiguousarray(V), centre, half, best, float(slack), int(max_levels),
                 left, right)
    core = compiled_core()
    if core is not None:  # the compiled core: nothing compiles at call time
        return core.bernstein_bound(*arguments)
    return _subdivide(*arguments)
