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
from drake_mh.optim.base import Optimizer, batched_choice

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

    # -- operators ----------------------------------------------------------------------

    def _blend(self, M: np.ndarray, Dd: np.ndarray) -> np.ndarray:
        a = self.randint(M.shape[1], M.shape[0])
        b = self.rng.random(M.shape[0])
        return _blend_kernel(M, Dd, a, b)

    def _sbx(self, M: np.ndarray, Dd: np.ndarray) -> np.ndarray:
        u = self.rng.random(M.shape)
        e = 1.0 / (self.config.eta_c + 1.0)
        beta = np.where(u <= 0.5, (2.0 * u) ** e, (0.5 / (1.0 - u)) ** e)
        swap = self.rng.random(M.shape) < 0.5                      # per-variable crossover
        beta = np.where(swap, beta, 1.0)
        C1 = 0.5 * ((1 + beta) * M + (1 - beta) * Dd)
        C2 = 0.5 * ((1 - beta) * M + (1 + beta) * Dd)
        return self.clip(np.concatenate([C1, C2]))

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, N, D, k = self.config, self.pop_size, self.dim, self.n_keep
        n_off = N - k
        pairs = math.ceil(n_off / 2)
        parents = batched_choice(self.rng, self.p_rank, 2 * pairs)
        M, Dd = self.X[parents[:pairs]], self.X[parents[pairs:]]
        kids = self._blend(M, Dd) if c.crossover == "blend" else self._sbx(M, Dd)
        Y = np.concatenate([self.X[:k], kids[:n_off]])
        mask = self.rng.random((N - 1, D)) < c.mutation_rate
        if mask.any():
            body = Y[1:]
            if c.mutation == "reset":
                R = self.lower + self.rng.random((N - 1, D)) * self.width
            else:
                u = self.rng.random((N - 1, D))
                e = 1.0 / (c.eta_m + 1.0)
                delta = np.where(u < 0.5, (2.0 * u) ** e - 1.0, 1.0 - (2.0 * (1.0 - u)) ** e)
                R = np.clip(body + delta * self.width, self.lower, self.upper)
            np.copyto(body, R, where=mask)
        changed = np.zeros(N, dtype=bool)
        changed[k:] = True
        changed[1:] |= mask.any(axis=1)
        self._Y, self._changed = Y, np.flatnonzero(changed)
        return Y[self._changed]

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            Y, FY = X.copy(), F.copy()
        else:
            Y, FY = self._Y, self.F.copy()      # unchanged survivors keep their values
            FY[self._changed] = F
        order = np.argsort(FY, kind="stable")
        self.X, self.F = Y[order], FY[order]


@numba.njit(cache=True)
def _blend_kernel(M, Dd, a, b):
    """Haupt's single-point blend crossover for parent pairs ``(M[r], Dd[r])``.

    Gene ``a[r]`` blends with weight ``b[r]``; the genes right of it are swapped. Returns
    the ``2n`` children: first children of every pair, then second children.
    """
    n, D = M.shape
    C = np.empty((2 * n, D))
    for r in range(n):
        for d in range(D):
            if d > a[r]:
                C[r, d] = Dd[r, d]
                C[n + r, d] = M[r, d]
            else:
                C[r, d] = M[r, d]
                C[n + r, d] = Dd[r, d]
        ma, da = M[r, a[r]], Dd[r, a[r]]
        C[r, a[r]] = ma - b[r] * (ma - da)
        C[n + r, a[r]] = da + b[r] * (ma - da)
    return C
