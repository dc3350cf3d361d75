"""Artificial rabbits optimization, and the ESM paper's AMNN arrangement of it.

Sources: L. Wang, Q. Cao, Z. Zhang, S. Mirjalili, W. Zhao, "Artificial rabbits
optimization: A new bio-inspired meta-heuristic algorithm for solving engineering
optimization problems", Engineering Applications of Artificial Intelligence 114:105082,
2022 ("ARO"); eqs. (12)-(21) of the ESM paper ("AMNN": the same agent update arranged as
L layers of P agent neurons; layer l = generation t, L = T).

Per rabbit i and generation t of T (r* ~ U(0, 1) scalars per rabbit)::

    A = 4 (1 - t/T) ln(1/r1)                                    energy (ARO 15, ESM 12)
    c = mask of ceil(r2 D) random dimensions                     (ARO 4, ESM 13)
    R = (e - exp(((t - 1)/T)^2)) sin(2 pi r3) c                  (ARO 2-3, ESM 14)
    A > 1, detour foraging towards a random other rabbit j:
        aro : v = x_j + R o (x_i - x_j) + round(0.5 (0.05 + r4)) n1,  n1 ~ N(0, 1)   (ARO 1)
        amnn: v = x_i + R o (x_j - x_i)                                            (ESM 15)
    A <= 1, random hiding in a burrow near x_i (g = one random dimension):
        b = x_i + H g o x_i,  H = (T - t + 1)/T n2                   (ARO 8, 13; ESM 16-17)
        v = x_i + R o (r5 b - x_i)                                   (ARO 11, ESM 18)
        n2 ~ N(0, 1) for ``aro`` (the authors' code), U(0, 1) for ``amnn`` (ESM text)
    greedy: x_i <- v if f(v) < f(x_i)                                (ARO 16, ESM 20)

Bound handling: ``aro`` re-draws out-of-box components uniformly (authors' code);
``amnn`` projects onto the box (ESM eq. (19), the velocity-feasibility test of eq. (19)
belongs to the problem, not the optimizer).

Warm start: ``x0`` of shape ``(K, D)``, ``K <= pop_size``, replaces the first K rabbits of
the initial population; passing the previous control step's population
(``OptimizeResult.population``) continues the search, as the ESM control loop does.

Note the hiding move scales a coordinate by itself (``H g o x_i``) and pulls towards
``r5 b`` (a shrunk copy of x_i): both are attracted by the origin, a source of centre bias.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer

VARIANTS = ("aro", "amnn")


@dataclass(frozen=True)
class AROConfig:
    """ARO hyper-parameters.

    Attributes:
        variant: ``"aro"`` (Wang et al. 2022 and their code) or ``"amnn"`` (ESM eqs. 12-21).
    """

    variant: str = "aro"

    def __post_init__(self):
        if self.variant not in VARIANTS:
            raise InvalidArgument(f"aro: variant must be one of {VARIANTS}; got {self.variant!r}")


class ARO(Optimizer):
    """Artificial rabbits optimization (Wang et al. 2022), default 50 rabbits."""

    name = "aro"
    Config = AROConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 50

    def _start(self) -> None:
        self.X = None
        self.T = max(1, math.ceil(self.budget / self.pop_size) - 1)
        self.amnn = self.config.variant == "amnn"

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        P, D = self.pop_size, self.dim
        t, T = min(self.nit, self.T), self.T
        X = self.X
        U = self.rng.random((P, 6))
        A = 4.0 * (1.0 - t / T) * np.log(1.0 / np.maximum(U[:, 0], 1e-300))
        n_dims = np.ceil(U[:, 1] * D)
        # c: n_dims random distinct dimensions per rabbit (rank of random keys < n_dims)
        ranks = np.argsort(np.argsort(self.rng.random((P, D)), axis=1), axis=1)
        c = ranks < n_dims[:, None]
        Lw = (math.e - math.exp(((t - 1) / T) ** 2)) * np.sin(2.0 * np.pi * U[:, 2])
        R = Lw[:, None] * c
        j = self.others(P)
        Xj = X[j]
        if self.amnn:
            detour = X + R * (Xj - X)                                              # ESM (15)
            n2 = U[:, 4]
        else:
            jump = np.round(0.5 * (0.05 + U[:, 3])) * self.rng.standard_normal(P)
            detour = Xj + R * (X - Xj) + jump[:, None]                             # ARO (1)
            n2 = self.rng.standard_normal(P)
        g = np.zeros((P, D))
        g[np.arange(P), self.randint(D, P)] = 1.0
        H = (T - t + 1) / T * n2
        b = X + H[:, None] * g * X                                                 # ARO (13)
        hide = X + R * (U[:, 5:6] * b - X)                                         # ARO (11)
        V = np.where((A > 1.0)[:, None], detour, hide)
        return self.clip(V) if self.amnn else self.reinit(V)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        better = F < self.F                                                         # ESM (20)
        np.copyto(self.X, X, where=better[:, None])
        np.copyto(self.F, F, where=better)
