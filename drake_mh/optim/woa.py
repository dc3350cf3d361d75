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

``A`` and ``C`` are *scalars per whale* from two independent draws r1, r2 (the paper's
``|A| < 1`` test on a vector only makes sense for a scalar; drawing them per dimension is a
different algorithm, and so is mealpy's one shared r: ``woa_greedy`` below). ``p`` and
``l`` are scalars per whale too. The reference code's
``l = (a2 - 1) rand + 1`` with ``a2`` going from -1 to -2 is not used: ``l ~ U(-1, 1)``
as in the paper. The population moves unconditionally (no greedy selection); X* is updated
whenever a better point is found.

Bound handling: clip onto the box (the reference code clamps to the bounds).

Variant ``woa_greedy`` (:class:`WOAGreedy`): mealpy 3.0.3's ``OriginalWOA``, a *different*
algorithm that users of mealpy know as "WOA". Per whale, with the same ``a``, ``p``, ``l``, ``b``::

    r ~ U(0, 1) one draw:  A = 2 a r - a,  C = 2 r   (so C = 1 + A/a)
    p < 0.5 and |A| < 1:   X' = X* - A |C X* - X|
    p < 0.5 and |A| >= 1:  X' = X_box - A |C X_box - X|,   X_box ~ U(box)  (a fresh point,
                                                                           not a random whale)
    p >= 0.5:              X' = |X* - X| e^{b l} cos(2 pi l) + X*
    clip X' onto the box;  X <- X' only if f(X') < f(X)           (greedy selection)

mealpy's ``a = 2 - 2 epoch / max_epoch`` is ``2 - 2 t/T`` here as for ``woa``. mealpy's
default ("single") mode evaluates each whale at once and keeps the better of old and new;
since its X* changes only between generations and no whale's move reads another whale,
evaluating the generation as one batch, as here, gives the same algorithm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import greedy_replace
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
        a = self.config.a_max * (1.0 - self.progress())
        R = self.rng.random((self.pop_size, 5))
        return _move(self.X, self.best_x, R, a, self.config.b, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        self.X, self.F = X, F.copy()


class WOAGreedy(WOA):
    """mealpy 3.0.3's WOA variant: shared ``r`` for A and C, a uniform box point for
    ``|A| >= 1``, greedy selection (module docstring); default 30 whales.

    Not the paper's algorithm (``woa`` is): offered because it is the WOA that mealpy
    users know and it is stronger on the shifted CEC 2017 functions
    (``studies/optimizer_peers.py``).
    """

    name = "woa_greedy"

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        a = self.config.a_max * (1.0 - self.progress())
        R = self.rng.random((self.pop_size, 3 + self.dim))
        return _move_greedy(self.X, self.best_x, R, a, self.config.b, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        greedy_replace(self.X, self.F, X, F, False)          # strictly better only (mealpy)


@numba.njit(cache=True)
def _move(X, Xb, R, a, b, lower, upper):
    """Eqs. (2.1)-(2.8) for every whale, then clip onto the box.

    ``R (P, 5)`` per whale: r1, r2, p, l (as ``2 u - 1``) and the random whale
    (``floor(u P)``). Returns the new positions ``(P, D)``.
    """
    P, D = X.shape
    Xn = np.empty((P, D))
    for i in range(P):
        A = 2.0 * a * R[i, 0] - a                                   # (2.3)
        C = 2.0 * R[i, 1]                                           # (2.4)
        if R[i, 2] < 0.5:
            if abs(A) < 1.0:                                        # (2.1)-(2.2): encircle X*
                for d in range(D):
                    Xn[i, d] = Xb[d] - A * abs(C * Xb[d] - X[i, d])
            else:                                                   # (2.7)-(2.8): random whale
                k = min(int(R[i, 4] * P), P - 1)
                for d in range(D):
                    Xn[i, d] = X[k, d] - A * abs(C * X[k, d] - X[i, d])
        else:                                                       # (2.5): spiral
            l = 2.0 * R[i, 3] - 1.0
            s = np.exp(b * l) * np.cos(2.0 * np.pi * l)
            for d in range(D):
                Xn[i, d] = abs(Xb[d] - X[i, d]) * s + Xb[d]
        for d in range(D):
            Xn[i, d] = min(max(Xn[i, d], lower[d]), upper[d])
    return Xn


@numba.njit(cache=True)
def _move_greedy(X, Xb, R, a, b, lower, upper):
    """mealpy 3.0.3 ``OriginalWOA``'s move for every whale, then clip onto the box.

    ``R (P, 3 + D)`` per whale: r (gives both A and C), p, l (as ``2 u - 1``), then ``D``
    uniforms for the box point ``X_box = lower + u (upper - lower)`` (used only when
    ``p < 0.5`` and ``|A| >= 1``). Returns the new positions ``(P, D)``.
    """
    P, D = X.shape
    Xn = np.empty((P, D))
    for i in range(P):
        A = 2.0 * a * R[i, 0] - a
        C = 2.0 * R[i, 0]                                           # the same r as A
        if R[i, 1] < 0.5:
            if abs(A) < 1.0:                                        # encircle X*
                for d in range(D):
                    Xn[i, d] = Xb[d] - A * abs(C * Xb[d] - X[i, d])
            else:                                                   # around a uniform box point
                for d in range(D):
                    xr = lower[d] + R[i, 3 + d] * (upper[d] - lower[d])
                    Xn[i, d] = xr - A * abs(C * xr - X[i, d])
        else:                                                       # spiral
            l = 2.0 * R[i, 2] - 1.0
            s = np.exp(b * l) * np.cos(2.0 * np.pi * l)
            for d in range(D):
                Xn[i, d] = abs(Xb[d] - X[i, d]) * s + Xb[d]
        for d in range(D):
            Xn[i, d] = min(max(Xn[i, d], lower[d]), upper[d])
    return Xn
