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
def _acceleration_kernel(X, attractors, M, W, G, eps):
    """Eqs. (7)-(10): ``a_i = sum_j W_ij G M_j (x_j - x_i) / (|x_j - x_i| + eps)``, j != i.

    ``attractors (k,)`` are the Kbest agents (column j of ``W (N, k)`` belongs to agent
    ``attractors[j]``). A compiled double loop: for N = 50 it costs a few microseconds where
    the equivalent numpy expression costs tens (per-call overhead).
    """
    N, D = X.shape
    a = np.zeros((N, D))
    diff = np.empty(D)
    for i in range(N):
        for jj in range(attractors.shape[0]):
            j = attractors[jj]
            if j == i:
                continue
            r2 = 0.0
            for d in range(D):
                diff[d] = X[j, d] - X[i, d]
                r2 += diff[d] * diff[d]
            w = W[i, jj] * G * M[j] / (np.sqrt(r2) + eps)
            for d in range(D):
                a[i, d] += w * diff[d]
    return a


def masses(F: np.ndarray) -> np.ndarray:
    """Normalized inertial masses ``M (N,)`` from objective values, eqs. (14)-(16).

    Non-finite values get mass 0; equal values give equal masses.
    """
    best, worst = F.min(), F.max()
    if np.isfinite(worst):            # all finite (NaN was mapped to +inf by the base class)
        if worst == best:
            return np.full(len(F), 1.0 / len(F))
        m = (F - worst) * (1.0 / (best - worst))
        return m * (1.0 / m.sum())
    fin = np.isfinite(F)
    if not fin.all():
        if not fin.any():
            return np.full(len(F), 1.0 / len(F))
        Ff = F[fin]
        best, worst = Ff.min(), Ff.max()
    else:
        best, worst = F.min(), F.max()
    if worst == best:
        m = fin.astype(float)
    else:
        m = np.where(fin, (F - worst) / (best - worst), 0.0) if not fin.all() else (F - worst) / (best - worst)
    return m / m.sum()


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

    def acceleration(self) -> np.ndarray:
        """Gravitational acceleration ``a (N, D)`` of eqs. (7)-(10) at the current state."""
        c, N = self.config, self.pop_size
        tau = self.progress()
        G = c.G0 * np.exp(-c.alpha * tau)
        M = masses(self.F)
        k = int(round(N * (c.final_fraction + (1.0 - tau) * (1.0 - c.final_fraction))))
        k = min(max(k, 1), N)
        W = self.rng.random((N, k))
        attractors = np.argsort(self.F, kind="stable")[:k] if k < N else np.arange(N)
        return _acceleration_kernel(self.X, attractors, M, W, G, _EPS)

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        a = self.acceleration()
        self.V = self.rng.random(self.V.shape) * self.V + a              # eq. (11)
        Xn = self.X + self.V                                             # eq. (12)
        return self.reinit(Xn)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X, F.copy()
