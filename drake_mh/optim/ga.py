"""Real-coded genetic algorithm (the cyclic paper's variant).

Sources: the cyclic paper (Sect. IV-B and V: real-coded GA, "selection rate 0.5, mutation
rate 0.1", random-resetting mutation, 20 individuals) whose vocabulary is that of
R. L. Haupt & S. E. Haupt, *Practical Genetic Algorithms*, 2nd ed., Wiley 2004, ch. 3
(continuous GA). Options: simulated binary crossover (SBX; Deb & Agrawal, Complex Systems
9:115-148, 1995) and polynomial mutation (Deb & Goyal 1996).

One generation (N individuals kept sorted by f)::

    N_keep = ceil(selection_rate N)              natural selection: the best half survives
    parents: rank-weighted roulette over the N_keep survivors, p_n = (N_keep - n + 1) / sum(1..N_keep)
    crossover (Haupt's single-point blend): gene a ~ U{1..D}, b ~ U(0, 1)
        c1[a] = m[a] - b (m[a] - d[a]),  c2[a] = d[a] + b (m[a] - d[a]),
        genes right of a swapped between the parents; children replace the N - N_keep worst
    mutation (random resetting): every gene of every individual except the elite (best)
        is replaced by a U(lower, upper) value with probability mutation_rate
        (Haupt uses exactly ceil(mu (N - 1) D) genes; this is the same in expectation)

Only individuals that changed (children and mutated survivors) are evaluated, so a
generation costs about ``N - N_keep + mutation_rate N_keep D`` evaluations, not N.

Bound handling: blend crossover and resetting mutation stay inside the box by
construction; with SBX / polynomial mutation the children are clipped onto the box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer

CROSSOVERS = ("blend", "sbx")
MUTATIONS = ("reset", "polynomial")


@dataclass(frozen=True)
class GAConfig:
    """Real-coded GA hyper-parameters (cyclic paper defaults).

    Attributes:
        selection_rate: fraction of the population that survives (0.5, cyclic paper).
        mutation_rate: per-gene mutation probability (0.1, cyclic paper).
        crossover: ``"blend"`` (Haupt, default) or ``"sbx"``.
        mutation: ``"reset"`` (random resetting, default) or ``"polynomial"``.
        eta_c: SBX distribution index (15).
        eta_m: polynomial-mutation distribution index (20).
    """

    selection_rate: float = 0.5
    mutation_rate: float = 0.1
    crossover: str = "blend"
    mutation: str = "reset"
    eta_c: float = 15.0
    eta_m: float = 20.0

    def __post_init__(self):
        if not (0 < self.selection_rate < 1):
            raise InvalidArgument(f"ga: selection_rate must be in (0, 1); got {self.selection_rate}")
        if not (0 <= self.mutation_rate <= 1):
            raise InvalidArgument(f"ga: mutation_rate must be in [0, 1]; got {self.mutation_rate}")
        if self.crossover not in CROSSOVERS:
            raise InvalidArgument(f"ga: crossover must be one of {CROSSOVERS}; got {self.crossover!r}")
        if self.mutation not in MUTATIONS:
            raise InvalidArgument(f"ga: mutation must be one of {MUTATIONS}; got {self.mutation!r}")
        if self.eta_c < 0 or self.eta_m < 0:
            raise InvalidArgument("ga: eta_c and eta_m must be >= 0")


class GA(Optimizer):
    """Real-coded GA, default 40 individuals (the cyclic paper used 20 for 1-4 variables)."""

    name = "ga"
    Config = GAConfig
    min_pop_size = 4

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 40

    def _start(self) -> None:
        N = self.pop_size
        self.X = None
        self.n_keep = min(max(2, math.ceil(self.config.selection_rate * N)), N - 1)
        ranks = np.arange(self.n_keep, 0, -1, dtype=float)
        self.p_rank = ranks / ranks.sum()
        self._cum_rank = np.cumsum(self.p_rank)
        self._blend = self.config.crossover == "blend"
        self._reset = self.config.mutation == "reset"

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, N, D = self.config, self.pop_size, self.dim
        pairs = math.ceil((N - self.n_keep) / 2)
        n_cross = 2 * pairs if self._blend else 2 * pairs * D
        U = self.rng.random(2 * pairs + n_cross + 2 * (N - 1) * D)
        Y, self._changed = _offspring(self.X, self.n_keep, self._cum_rank, U, self._blend, self._reset,
                                      c.mutation_rate, c.eta_c, c.eta_m, self.lower, self.upper)
        self._Y = Y
        return Y[self._changed]

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = _sorted(X, F, np.arange(len(F)), F)
        else:                                   # unchanged survivors keep their values
            self.X, self.F = _sorted(self._Y, self.F, self._changed, F)


@numba.njit(cache=True)
def _offspring(X, n_keep, cum_rank, U, blend, reset, mutation_rate, eta_c, eta_m, lower, upper):
    """One generation's new population ``Y (N, D)`` and the indices of its changed rows.

    ``X (N, D)`` is sorted by f. Rows ``0..n_keep-1`` of Y are the survivors, the rest the
    children of parent pairs drawn by the rank roulette (cumulative probabilities
    ``cum_rank``); then every gene of rows ``1..N-1`` mutates with probability
    ``mutation_rate``. Uniforms in ``U``, in this order: ``2 pairs`` parent draws (mothers,
    then fathers); the crossover's (blend: gene a and weight b per pair; SBX: ``u`` and
    the per-variable crossover test, ``pairs x D`` each); the ``(N - 1) x D`` mutation
    tests; the ``(N - 1) x D`` mutation values.
    """
    N, D = X.shape
    pairs = (N - n_keep + 1) // 2
    Y = np.empty((N, D))
    Y[:n_keep] = X[:n_keep]
    C = np.empty((2 * pairs, D))             # first children of every pair, then second
    o = 2 * pairs                            # offset of the crossover draws in U
    for r in range(pairs):
        m = _roulette(cum_rank, U[r])
        f = _roulette(cum_rank, U[pairs + r])
        if blend:                            # Haupt's single-point blend
            a = min(int(U[o + r] * D), D - 1)
            b = U[o + pairs + r]
            for d in range(D):
                if d > a:
                    C[r, d], C[pairs + r, d] = X[f, d], X[m, d]
                else:
                    C[r, d], C[pairs + r, d] = X[m, d], X[f, d]
            ma, da = X[m, a], X[f, a]
            C[r, a] = ma - b * (ma - da)
            C[pairs + r, a] = da + b * (ma - da)
        else:                                # SBX, per-variable crossover with probability 0.5
            e = 1.0 / (eta_c + 1.0)
            for d in range(D):
                u = U[o + r * D + d]
                if U[o + pairs * D + r * D + d] < 0.5:
                    beta = (2.0 * u) ** e if u <= 0.5 else (0.5 / (1.0 - u)) ** e
                else:
                    beta = 1.0
                c1 = 0.5 * ((1.0 + beta) * X[m, d] + (1.0 - beta) * X[f, d])
                c2 = 0.5 * ((1.0 - beta) * X[m, d] + (1.0 + beta) * X[f, d])
                C[r, d] = min(max(c1, lower[d]), upper[d])
                C[pairs + r, d] = min(max(c2, lower[d]), upper[d])
    Y[n_keep:] = C[: N - n_keep]
    o += 2 * pairs if blend else 2 * pairs * D
    n_mut = (N - 1) * D                      # mutation tests at o, values at o + n_mut
    changed = np.zeros(N, dtype=np.bool_)
    changed[n_keep:] = True
    e = 1.0 / (eta_m + 1.0)
    for i in range(1, N):                    # row 0, the elite, never mutates
        for d in range(D):
            q = (i - 1) * D + d
            if U[o + q] < mutation_rate:
                u = U[o + n_mut + q]
                if reset:
                    Y[i, d] = lower[d] + u * (upper[d] - lower[d])
                else:                        # polynomial mutation
                    delta = (2.0 * u) ** e - 1.0 if u < 0.5 else 1.0 - (2.0 * (1.0 - u)) ** e
                    Y[i, d] = min(max(Y[i, d] + delta * (upper[d] - lower[d]), lower[d]), upper[d])
                changed[i] = True
    return Y, np.flatnonzero(changed)


@numba.njit(cache=True)
def _roulette(cum, u):
    """Index drawn with probabilities ``diff(cum)`` by the uniform ``u`` (first ``cum > u cum[-1]``)."""
    x = u * cum[-1]
    n = cum.shape[0]
    for i in range(n):
        if cum[i] > x:
            return i
    return n - 1


@numba.njit(cache=True)
def _sorted(Y, FY, changed, F):
    """``Y`` and its values sorted by value (stable); rows ``changed`` get the new values ``F``,
    the others keep ``FY``."""
    FY = FY.copy()
    for r in range(changed.shape[0]):
        FY[changed[r]] = F[r]
    order = np.argsort(FY, kind="mergesort")
    return Y[order], FY[order]
