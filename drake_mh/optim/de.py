"""Differential evolution, DE/rand/1/bin (vectorized).

Source: R. Storn & K. Price, "Differential Evolution - A Simple and Efficient Heuristic
for Global Optimization over Continuous Spaces", J. Global Optimization 11:341-359, 1997.

Why not ``scipy.optimize.differential_evolution``: scipy owns the loop, checks ``maxfun``
only between generations and evaluates its initial population and polishing step outside
any exact budget, so it cannot be made to stop at *exactly* ``budget`` evaluations nor be
driven by ask/tell. This is a faithful vectorized DE/rand/1/bin instead (scipy's default
strategy is best1bin; rand1bin is the classic of the paper)::

    v_i = x_r1 + F (x_r2 - x_r3),        r1, r2, r3, i distinct                 (eq. 4)
    u_ij = v_ij if rand_ij <= CR or j == jrand_i, else x_ij                     (eq. 5)
    x_i <- u_i if f(u_i) <= f(x_i)                                              (eq. 6)

Defaults F = 0.5, CR = 0.9 (Storn & Price's recommended start), NP = 10 D clipped to
[20, 100] (the paper suggests 5D-10D).

Bound handling: a trial component outside the box is set to the midpoint between the
parent's component and the violated bound (keeps feasibility without piling points on
the bounds or pulling them to the centre; a common DE repair, e.g. JADE).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import distinct_indices, greedy_replace
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class DEConfig:
    """DE/rand/1/bin hyper-parameters.

    Attributes:
        F: differential weight (0.5).
        CR: crossover probability (0.9).
    """

    F: float = 0.5
    CR: float = 0.9

    def __post_init__(self):
        if not (0 < self.F <= 2):
            raise InvalidArgument(f"de: F must be in (0, 2]; got {self.F}")
        if not (0 <= self.CR <= 1):
            raise InvalidArgument(f"de: CR must be in [0, 1]; got {self.CR}")


class DE(Optimizer):
    """DE/rand/1/bin (Storn & Price 1997)."""

    name = "de"
    Config = DEConfig
    min_pop_size = 4

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return int(min(max(10 * dim, 20), 100))

    def _start(self) -> None:
        self.X = None

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        P, D = self.pop_size, self.dim
        U = self.rng.random((P, D + 4))
        r = distinct_indices(U[:, :3], P, True)              # r1, r2, r3 != i, distinct
        return _trial(self.X, r, U, self.config.F, self.config.CR, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        greedy_replace(self.X, self.F, X, F, True)                               # eq. (6)


@numba.njit(cache=True)
def _trial(X, r, U, F, CR, lower, upper):
    """Eqs. (4)-(5) and the midpoint bound repair for every target vector ``x_i``.

    ``r (P, 3)``: the donors r1, r2, r3. ``U (P, D + 4)``: column 3 gives ``jrand``
    (``floor(u D)``), columns ``4..`` the crossover draws ``rand_ij`` (columns 0-2 drew
    the donors). Returns the trial vectors ``(P, D)``.
    """
    P, D = X.shape
    Xt = np.empty((P, D))
    for i in range(P):
        jrand = min(int(U[i, 3] * D), D - 1)
        a, b, c = r[i, 0], r[i, 1], r[i, 2]
        for d in range(D):
            x = X[i, d]
            if U[i, 4 + d] <= CR or d == jrand:                              # eq. (5)
                u = X[a, d] + F * (X[b, d] - X[c, d])                          # eq. (4)
                if u < lower[d]:
                    u = 0.5 * (x + lower[d])
                elif u > upper[d]:
                    u = 0.5 * (x + upper[d])
                x = u
            Xt[i, d] = x
    return Xt
