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

import numpy as np

from drake_mh.errors import InvalidArgument
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
        c, P, D = self.config, self.pop_size, self.dim
        X = self.X
        r = self.donors(P, P)
        V = X[r[:, 0]] + c.F * (X[r[:, 1]] - X[r[:, 2]])
        cross = self.rng.random((P, D)) <= c.CR
        cross[np.arange(P), self.randint(D, P)] = True
        U = np.where(cross, V, X)
        lo, hi = U < self.lower, U > self.upper
        if lo.any() or hi.any():
            U = np.where(lo, 0.5 * (X + self.lower), U)
            U = np.where(hi, 0.5 * (X + self.upper), U)
        return U

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        better = F <= self.F
        np.copyto(self.X, X, where=better[:, None])
        np.copyto(self.F, F, where=better)
