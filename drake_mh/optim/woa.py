"""Whale optimization algorithm.

Source: S. Mirjalili, A. Lewis, "The Whale Optimization Algorithm", Advances in
Engineering Software 95:51-67, 2016 (also eqs. (22)-(23) of the cyclic paper).

Equations (numbers of Mirjalili & Lewis 2016; X* = best so far, t/T = budget fraction)::

    a = 2 - 2 t/T                                                  (decreases 2 -> 0)
    A = 2 a r1 - a,   C = 2 r2          r1, r2 ~ U(0, 1)            (2.3), (2.4)
    p < 0.5 and |A| < 1:   X <- X* - A |C X* - X|                  (2.1), (2.2)
    p < 0.5 and |A| >= 1:  X <- X_rand - A |C X_rand - X|          (2.7), (2.8)
    p >= 0.5:              X <- |X* - X| e^{b l} cos(2 pi l) + X*  (2.5)
                           l ~ U(-1, 1), b = 1

``A`` and ``C`` are *scalars per whale* (the paper's ``|A| < 1`` test on a vector only
makes sense for a scalar; drawing them per dimension, as mealpy does, is a different
algorithm). ``p`` and ``l`` are scalars per whale too. The reference code's
``l = (a2 - 1) rand + 1`` with ``a2`` going from -1 to -2 is not used: ``l ~ U(-1, 1)``
as in the paper. The population moves unconditionally (no greedy selection); X* is updated
whenever a better point is found.

Bound handling: clip onto the box (the reference code clamps to the bounds).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class WOAConfig:
    """WOA hyper-parameters.

    Attributes:
        b: logarithmic-spiral shape constant (1, paper).
        a_max: start value of ``a`` (2, paper); it decreases linearly to 0.
    """

    b: float = 1.0
    a_max: float = 2.0

    def __post_init__(self):
        if self.a_max <= 0:
            raise InvalidArgument(f"woa: a_max must be > 0; got {self.a_max}")


class WOA(Optimizer):
    """Whale optimization algorithm (Mirjalili & Lewis 2016), default 30 whales."""

    name = "woa"
    Config = WOAConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 30

    def _start(self) -> None:
        self.X = None

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, P = self.config, self.pop_size
        a = c.a_max * (1.0 - self.progress())
        R = self.rng.random((P, 4))
        A = (2.0 * a * R[:, 0] - a)[:, None]                      # (P, 1) scalar per whale
        C = (2.0 * R[:, 1])[:, None]
        p = R[:, 2]
        l = (2.0 * R[:, 3] - 1.0)[:, None]
        X, Xb = self.X, self.best_x
        # encircling (|A| < 1) or search around a random whale (|A| >= 1)
        ref = np.where(np.abs(A) < 1.0, Xb, X[self.randint(P, P)])
        enc = ref - A * np.abs(C * ref - X)
        spiral = np.abs(Xb - X) * np.exp(c.b * l) * np.cos(2.0 * np.pi * l) + Xb
        Xn = np.where((p < 0.5)[:, None], enc, spiral)
        return self.clip(Xn)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X, F.copy()
