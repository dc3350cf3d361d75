"""Gravitational search algorithm.

Source: E. Rashedi, H. Nezamabadi-pour, S. Saryazdi, "GSA: A Gravitational Search
Algorithm", Information Sciences 179(13):2232-2248, 2009.

Equations (numbers of Rashedi et al. 2009; minimization, t/T = used budget fraction)::

    m_i = (fit_i - worst) / (best - worst),   M_i = m_i / sum_j m_j           (14)-(16)
    G(t) = G0 exp(-alpha t / T)                                               (28)
    a_i^d = sum_{j in Kbest, j != i} rand_ij G M_j (x_j^d - x_i^d) / (R_ij + eps)  (7)-(10)
    v_i^d <- rand_i^d v_i^d + a_i^d                                            (11)
    x_i^d <- x_i^d + v_i^d                                                     (12)

``R_ij`` is the Euclidean distance (the paper found R better than R^2); ``Kbest`` shrinks
linearly from all N agents to ``final_fraction`` (2 %) of them. Defaults G0 = 100,
alpha = 20, N = 50 are the paper's. ``G0`` is in the problem's units (the paper's boxes
are tens to hundreds wide), so very small or very large boxes may want another G0.

Bound handling: components that leave the box are re-drawn uniformly inside it, as in
the authors' reference code.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer

_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class GSAConfig:
    """GSA hyper-parameters (Rashedi et al. 2009, Sect. 4).

    Attributes:
        G0: initial gravitational constant (100).
        alpha: decay rate of G (20).
        final_fraction: fraction of agents in Kbest at the end (0.02).
    """

    G0: float = 100.0
    alpha: float = 20.0
    final_fraction: float = 0.02

    def __post_init__(self):
        if self.G0 <= 0 or self.alpha < 0:
            raise InvalidArgument("gsa: G0 must be > 0 and alpha >= 0")
        if not (0 < self.final_fraction <= 1):
            raise InvalidArgument("gsa: final_fraction must be in (0, 1]")


@numba.njit(cache=True)
def _masses_kernel(F):
    """Eqs. (14)-(16) for finite values; non-finite values get mass 0 (see :func:`masses`)."""
    N = F.shape[0]
    best, worst, n_fin = np.inf, -np.inf, 0
    for i in range(N):
        if np.isfinite(F[i]):
            best = min(best, F[i])
            worst = max(worst, F[i])
            n_fin += 1
    M = np.empty(N)
    if n_fin == 0:
        M[:] = 1.0 / N
        return M
    total = 0.0
    for i in range(N):
        if not np.isfinite(F[i]):
            M[i] = 0.0
        elif worst == best:
            M[i] = 1.0
        else:
            M[i] = (F[i] - worst) / (best - worst)
        total += M[i]
    for i in range(N):
        M[i] /= total
    return M


@numba.njit(cache=True, error_model="numpy")
def _acceleration_kernel(X, F, W, G, eps):
    """Eqs. (7)-(10): ``a_i = sum_j W_ji G M_j (x_j - x_i) / (|x_j - x_i| + eps)``, j != i.

    The masses ``M`` come from ``F`` (:func:`masses`); the attractors j are the ``k`` best
    agents (stable order, so ties go to the lower index; all N agents in index order when
    ``k = N``); row ``jj`` of ``W (k, N)`` holds the rand_ij of eq. (9) of the ``jj``-th
    attractor for every agent i. The loops run over the agents i innermost, on a
    dimension-major copy of ``X``: they vectorize (SIMD) and the sum over j keeps its
    order. ``error_model="numpy"``: no zero-division check (the divisor is ``>= eps``),
    which would stop the vectorization. Returns ``a (N, D)``.
    """
    N, D = X.shape
    k = W.shape[0]
    M = _masses_kernel(F)
    att = np.argsort(F, kind="mergesort")[:k] if k < N else np.arange(N)
    XT = np.ascontiguousarray(X.T)
    aT = np.zeros((D, N))
    r2 = np.empty(N)
    w = np.empty(N)
    for jj in range(k):
        j = att[jj]
        r2[:] = 0.0
        for d in range(D):
            xj = X[j, d]
            for i in range(N):
                diff = xj - XT[d, i]
                r2[i] += diff * diff
        gm = G * M[j]
        for i in range(N):
            w[i] = W[jj, i] * gm / (np.sqrt(r2[i]) + eps)
        w[j] = 0.0                                 # no force of an agent on itself
        for d in range(D):
            xj = X[j, d]
            for i in range(N):
                aT[d, i] += w[i] * (xj - XT[d, i])
    return np.ascontiguousarray(aT.T)


@numba.njit(cache=True)
def _move(X, V, F, W, U, G, eps, lower, upper):
    """Eqs. (7)-(12) for every agent, then out-of-box components re-drawn uniformly.

    ``W (k, N)``: the rand_ij of eq. (9) (see :func:`_acceleration_kernel`); ``U (2, N, D)``:
    rand_i^d of eq. (11), then the uniforms of the re-draws. ``V`` is updated in place;
    returns the new positions.
    """
    N, D = X.shape
    a = _acceleration_kernel(X, F, W, G, eps)
    Xn = np.empty((N, D))
    for i in range(N):
        for d in range(D):
            v = U[0, i, d] * V[i, d] + a[i, d]                                  # eq. (11)
            V[i, d] = v
            x = X[i, d] + v                                                     # eq. (12)
            if x < lower[d] or x > upper[d]:
                x = lower[d] + U[1, i, d] * (upper[d] - lower[d])
            Xn[i, d] = x
    return Xn


def masses(F: np.ndarray) -> np.ndarray:
    """Normalized inertial masses ``M (N,)`` from objective values, eqs. (14)-(16).

    ``m_i = (f_i - worst) / (best - worst)``, ``M_i = m_i / sum_j m_j`` over the finite
    values; non-finite values get mass 0; equal values give equal masses; if no value is
    finite every agent gets ``1 / N``.
    """
    return _masses_kernel(np.ascontiguousarray(F, dtype=float))


class GSA(Optimizer):
    """Gravitational search algorithm (Rashedi et al. 2009), default N = 50 agents."""

    name = "gsa"
    Config = GSAConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 50

    def _start(self) -> None:
        self.X = None
        self.V = np.zeros((self.pop_size, self.dim))

    def schedule(self) -> tuple[float, int]:
        """``G(t)`` of eq. (28) and the size of Kbest at the current budget fraction."""
        c, N = self.config, self.pop_size
        tau = self.progress()
        G = c.G0 * math.exp(-c.alpha * tau)
        k = int(round(N * (c.final_fraction + (1.0 - tau) * (1.0 - c.final_fraction))))
        return G, min(max(k, 1), N)

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        N, D = self.pop_size, self.dim
        G, k = self.schedule()
        U = self.rng.random(N * k + 2 * N * D)
        W, U = U[: N * k].reshape(k, N), U[N * k:].reshape(2, N, D)
        return _move(self.X, self.V, self.F, W, U, G, _EPS, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X, F.copy()
