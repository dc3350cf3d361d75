"""Artificial bee colony.

Sources: D. Karaboga, "An idea based on honey bee swarm for numerical optimization",
Tech. Rep. TR06, Erciyes University, 2005; D. Karaboga & B. Basturk, "A powerful and
efficient algorithm for numerical function optimization: artificial bee colony (ABC)
algorithm", J. Global Optimization 39:459-471, 2007; eqs. (1)-(3) of the ABC paper.

A colony of ``pop_size`` bees: half employed, half onlookers; ``SN = pop_size // 2`` food
sources. One cycle (equation numbers of the ABC paper)::

    employed:  v_ij = x_ij + phi_ij (x_ij - x_kj), k != i random, one random j,
               phi ~ U(-1, 1); greedy selection; trial_i += 1 if not improved       (1)
    onlooker:  source i chosen with p_i = fit_i / sum fit, fit = 1 / (1 + f) for f >= 0,
               1 + |f| otherwise; same move and greedy selection                     (2)
    scout:     the source with the largest trial count > limit is replaced by a
               U(lower, upper) point (at most one scout per cycle)                   (3)

``limit`` defaults to ``SN * D`` (Karaboga & Basturk 2007); the ABC paper uses "the number
of employed bees" (``limit=SN``). The onlookers of a cycle are evaluated as one batch:
when several choose the same source, the best of their candidates competes with it (the
serial algorithm would let later onlookers start from an already improved source).

Bound handling: the moved coordinate is clipped onto the box (Karaboga's code).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class ABCConfig:
    """ABC hyper-parameters.

    Attributes:
        limit: abandonment limit in cycles; ``None`` means ``SN * D``.
    """

    limit: int | None = None

    def __post_init__(self):
        if self.limit is not None and (not isinstance(self.limit, (int, np.integer)) or self.limit < 1):
            raise InvalidArgument(f"abc: limit must be an integer >= 1 or None; got {self.limit!r}")


def abc_fitness(F: np.ndarray) -> np.ndarray:
    """Karaboga's fitness ``1 / (1 + f)`` for ``f >= 0`` and ``1 + |f|`` otherwise."""
    if F.min() >= 0:
        return 1.0 / (1.0 + F)
    return np.where(F >= 0, 1.0 / (1.0 + np.abs(F)), 1.0 + np.abs(F))


class ABC(Optimizer):
    """Artificial bee colony (Karaboga 2005), default colony of 40 bees (20 sources)."""

    name = "abc"
    Config = ABCConfig
    min_pop_size = 4

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 40

    def _start(self) -> None:
        self.SN = self.pop_size // 2
        self.limit = self.config.limit if self.config.limit is not None else self.SN * self.dim
        self.X = None
        self.trial = np.zeros(self.SN, dtype=np.int64)
        self.phase = "init"
        self._all = np.arange(self.SN)

    def _ask(self) -> np.ndarray:
        if self.phase == "init":
            return self.initial_population(self.SN)
        if self.phase == "scout":
            self._idx = np.array([self._scout])
            return self.lower + self.rng.random((1, self.dim)) * self.width       # eq. (3)
        if self.phase == "employed":
            self._idx = self._all
        else:   # onlookers: roulette on Karaboga's fitness, eq. (2)
            self._idx = _roulette_kernel(self.F, self.rng.random(self.SN))
        U = self.rng.random((3, len(self._idx)))
        return _neighbours_kernel(self.X, self._idx, U, self.lower, self.upper)  # eq. (1)

    def _greedy(self, idx: np.ndarray, V: np.ndarray, F: np.ndarray) -> None:
        _greedy_kernel(self.X, self.F, self.trial, idx, V, F, idx is self._all)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.phase == "init":
            self.X, self.F = X.copy(), F.copy()
            self.phase = "employed"
            return
        if self.phase == "scout":
            i = self._idx[0]
            self.X[i], self.F[i], self.trial[i] = X[0], F[0], 0
            self.phase = "employed"
            return
        self._greedy(self._idx, X, F)
        if self.phase == "employed":
            self.phase = "onlooker"
            return
        i = int(self.trial.argmax())
        if self.trial[i] > self.limit:
            self._scout = i
            self.phase = "scout"
        else:
            self.phase = "employed"


@numba.njit(cache=True)
def _roulette_kernel(F, u):
    """Onlooker sources: for each uniform ``u[r]`` the source index drawn with probabilities
    ``fit / sum(fit)``, ``fit`` = :func:`abc_fitness` of ``F`` (first cumulative fitness
    ``> u[r] sum(fit)``)."""
    SN = F.shape[0]
    cum = np.empty(SN)
    total = 0.0
    for s in range(SN):
        total += 1.0 / (1.0 + F[s]) if F[s] >= 0 else 1.0 + abs(F[s])
        cum[s] = total
    idx = np.empty(u.shape[0], dtype=np.int64)
    for r in range(u.shape[0]):
        x = u[r] * total
        lo, hi = 0, SN - 1                    # binary search, clamped to the last source
        while lo < hi:
            mid = (lo + hi) // 2
            if cum[mid] > x:
                hi = mid
            else:
                lo = mid + 1
        idx[r] = lo
    return idx


@numba.njit(cache=True)
def _neighbours_kernel(X, idx, U, lower, upper):
    """Eq. (1): ``v_ij = x_ij + phi (x_ij - x_kj)`` for one random j and k != i per source.

    ``U (3, n)`` holds the uniform draws for k, j and phi of each candidate; the moved
    coordinate is clipped to the box (the usual ABC bound handling).
    """
    SN, D = X.shape
    n = idx.shape[0]
    V = np.empty((n, D))
    for r in range(n):
        i = idx[r]
        k = (i + 1 + int(U[0, r] * (SN - 1))) % SN
        j = int(U[1, r] * D)
        phi = 2.0 * U[2, r] - 1.0
        for d in range(D):
            V[r, d] = X[i, d]
        v = X[i, j] + phi * (X[i, j] - X[k, j])
        V[r, j] = min(max(v, lower[j]), upper[j])
    return V


@numba.njit(cache=True)
def _greedy_kernel(X, FX, trial, idx, V, F, employed):
    """Greedy selection of Steps 4 and 6, in place on the sources ``X, FX`` and ``trial``.

    Employed bees bring one candidate per source. Onlookers may pick a source several times:
    every visit counts in ``trial``, and the best of its candidates (the first on ties)
    competes with the source, resetting its trial counter if it wins.
    """
    SN, D = X.shape
    if employed:
        for s in range(SN):
            if F[s] < FX[s]:
                for d in range(D):
                    X[s, d] = V[s, d]
                FX[s] = F[s]
                trial[s] = 0
            else:
                trial[s] += 1
        return
    best = np.full(SN, np.inf)
    pick = np.full(SN, -1)
    for r in range(idx.shape[0]):
        s = idx[r]
        trial[s] += 1
        if F[r] < best[s]:
            best[s] = F[r]
            pick[s] = r
    for s in range(SN):
        r = pick[s]
        if r >= 0 and F[r] < FX[s]:
            for d in range(D):
                X[s, d] = V[r, d]
            FX[s] = F[r]
            trial[s] = 0
