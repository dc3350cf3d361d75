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
``h`` is halved (de Casteljau), so pieces whose bound exceeds the largest value seen so far by
more than ``slack`` are halved, up to ``max_levels`` times; a piece still unsettled then keeps
its (valid, pessimistic) bound.
"""

from __future__ import annotations

import functools
from math import comb

import numpy as np

__all__ = ["kinematic_bound", "piece_degree"]


def piece_degree(trajectory) -> int:
    """Degree of ``q(t)`` on a piece between breaks (see the module docstring)."""
    degree = trajectory.path.c.shape[0] - 1
    if trajectory.timing is not None:
        degree *= trajectory.timing.c.shape[0] - 1
    return int(degree)


def _to_bernstein(u: tuple) -> np.ndarray:
    """``M`` with ``b = M v``: values at the nodes ``u`` (``n + 1`` distinct points of [0, 1]) to
    the Bernstein coefficients of the degree-``n`` polynomial through them."""
    n = len(u) - 1
    basis = np.array([[comb(n, i) * uj**i * (1.0 - uj) ** (n - i) for i in range(n + 1)] for uj in u])
    return np.linalg.inv(basis)


@functools.lru_cache(maxsize=16)
def _interpolation(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev-Lobatto nodes ``u (n+1,)`` on [0, 1] and their ``M`` (values -> Bernstein)."""
    if n == 0:
        return np.array([0.5]), np.ones((1, 1))
    u = 0.5 * (1.0 - np.cos(np.pi * np.arange(n + 1) / n))
    return u, _to_bernstein(tuple(u))


def kinematic_bound(trajectory, order: int, to_ratio, t0: np.ndarray, t1: np.ndarray, best: np.ndarray,
                    samples=None, slack: float = 1e-8, max_levels: int = 30) -> np.ndarray:
    """Per joint, an upper bound of ``to_ratio(q^(order)(t))`` over the pieces ``[t0, t1]``.

    Args:
        trajectory: the :class:`~drake_mh.trajectories.trajectory.Trajectory`.
        order: 0 (position) .. 3 (jerk).
        to_ratio: maps ``(lo, hi)`` — the per-joint range ``(..., nq)`` of the Bernstein
            coefficients (or of values) — to ratios ``(..., nq)`` (e.g. ``max(|lo|, |hi|) / limit``).
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
    best = np.array(best, dtype=float)
    certified = np.full_like(best, -np.inf)
    a, b = np.asarray(t0, float), np.asarray(t1, float)
    for level in range(max_levels + 1):
        if not a.size:
            break
        if level == 0 and samples is not None and len(samples[0]) > n:
            tau, V_all = samples
            pick = np.unique(np.round(np.linspace(0, len(tau) - 1, n + 1)).astype(int))
            V, M0 = V_all[:, pick], _to_bernstein(tuple(np.asarray(tau)[pick]))
        else:
            h = b - a
            eps = 1e-9 * h  # each piece's own polynomial at its ends (one-sided, as in certify)
            T = np.clip(a[:, None] + u[None, :] * h[:, None], (a + eps)[:, None], (b - eps)[:, None])
            V, M0 = trajectory.derivatives(T.ravel(), order)[order].reshape(len(a), n + 1, -1), M  # (P, n+1, nq)
        B = np.einsum("ij,pjk->pik", M0, V)
        bound = to_ratio(B.min(axis=1), B.max(axis=1))                                   # (P, nq)
        seen = to_ratio(V.min(axis=1), V.max(axis=1))
        best = np.maximum(best, seen.max(axis=0))
        open_ = np.any(bound > best + slack, axis=1)
        if level == max_levels:
            open_[:] = False
        if np.any(~open_):
            certified = np.maximum(certified, bound[~open_].max(axis=0))
        mid = 0.5 * (a[open_] + b[open_])
        a, b = np.concatenate([a[open_], mid]), np.concatenate([mid, b[open_]])
    return np.maximum(certified, best)
