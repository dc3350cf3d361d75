"""Aquila optimizer.

Source: L. Abualigah, D. Yousri, M. Abd Elaziz, A. A. Ewees, M. A. A. Al-qaness,
A. H. Gandomi, "Aquila Optimizer: A novel meta-heuristic optimization algorithm",
Computers & Industrial Engineering 157:107250, 2021.

Four strategies (equation numbers of the paper; t = generation, T = generations the budget
allows, X_M = population mean, X_R = a random agent, rand ~ U(0, 1) scalar per agent)::

    t <= 2T/3, rand <= 0.5: X1 = X_best (1 - t/T) + (X_M - X_best rand)           (3)
    t <= 2T/3, rand >  0.5: X2 = X_best Levy(D) + X_R + (y - x) rand              (5)
    t >  2T/3, rand <= 0.5: X3 = (X_best - X_M) alpha - rand
                                 + ((UB - LB) rand + LB) delta                    (13)
    t >  2T/3, rand >  0.5: X4 = QF X_best - G1 X rand - G2 Levy(D) + rand G1      (14)

    Levy(D) = s u sigma / |v|^(1/beta), u, v ~ N(0, 1), s = 0.01, beta = 1.5      (6)-(7)
    y = r cos(theta), x = r sin(theta), r = r1 + U D1, theta = -omega D1 + 3 pi / 2 (8)-(10)
    D1 = 1..D, r1 = 10 (the paper allows 1..20), U = 0.00565, omega = 0.005
    QF = t^((2 rand - 1) / (1 - T)^2), G1 = 2 rand - 1, G2 = 2 (1 - t/T)          (15)-(17)

A new position replaces the old one only if it is better (greedy, as in the authors' code).
Note eqs. (3), (13) and (14) multiply *positions* (not differences) by random factors, so
the operators pull towards the origin: expect centre bias (Kudela 2022); the study measures it.
The Levy steps use Mantegna's algorithm with Gaussian ``u, v`` (the authors' code).

Bound handling: clip onto the box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class AOConfig:
    """Aquila-optimizer hyper-parameters (paper defaults).

    Attributes:
        alpha: exploitation adjustment of eq. (13) (0.1).
        delta: exploitation adjustment of eq. (13) (0.1).
        beta: Levy exponent (1.5).
        s: Levy scale (0.01).
        r1: spiral search cycles of eq. (9) (10; paper range 1..20).
        U: spiral constant (0.00565).
        omega: spiral constant (0.005).
    """

    alpha: float = 0.1
    delta: float = 0.1
    beta: float = 1.5
    s: float = 0.01
    r1: float = 10.0
    U: float = 0.00565
    omega: float = 0.005

    def __post_init__(self):
        if not (0 < self.beta <= 2):
            raise InvalidArgument(f"ao: Levy exponent beta must be in (0, 2]; got {self.beta}")


def levy_sigma(beta: float) -> float:
    """Mantegna's sigma_u for a Levy exponent ``beta`` (eq. (7) of the AO paper)."""
    return (math.gamma(1 + beta) * math.sin(math.pi * beta / 2)
            / (math.gamma((1 + beta) / 2) * beta * 2 ** ((beta - 1) / 2))) ** (1 / beta)


class AO(Optimizer):
    """Aquila optimizer (Abualigah et al. 2021), default 30 agents."""

    name = "ao"
    Config = AOConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 30

    def _start(self) -> None:
        c = self.config
        self.X = None
        self.T = max(2, math.ceil(self.budget / self.pop_size) - 1)
        self.sigma = levy_sigma(c.beta)
        D1 = np.arange(1, self.dim + 1)
        r = c.r1 + c.U * D1
        theta = -c.omega * D1 + 1.5 * np.pi
        self.spiral = r * np.cos(theta) - r * np.sin(theta)          # (y - x), eqs. (8)-(10)

    def _levy(self, n: int) -> np.ndarray:
        Z = self.rng.standard_normal((2, n, self.dim))
        return self.config.s * Z[0] * self.sigma / np.abs(Z[1]) ** (1.0 / self.config.beta)

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, P, D = self.config, self.pop_size, self.dim
        t, T = self.nit, self.T
        tau = min(t / T, 1.0)
        X, Xb = self.X, self.best_x
        XM = X.mean(axis=0)
        R = self.rng.random((P, 4))
        choose = R[:, 0] <= 0.5
        r = R[:, 1:2]
        if t <= 2.0 * T / 3.0:
            X1 = Xb * (1.0 - tau) + (XM - Xb * r)                                     # (3)
            XR = X[self.randint(P, P)]
            X2 = Xb * self._levy(P) + XR + self.spiral * r                            # (5)
            Xn = np.where(choose[:, None], X1, X2)
        else:
            box = self.lower + self.width * self.rng.random((P, D))
            X3 = (Xb - XM) * c.alpha - r + box * c.delta                              # (13)
            QF = float(t) ** ((2.0 * R[:, 2:3] - 1.0) / (1.0 - T) ** 2)               # (15)
            G1 = 2.0 * R[:, 3:4] - 1.0                                                # (16)
            G2 = 2.0 * (1.0 - tau)                                                    # (17)
            X4 = QF * Xb - G1 * X * r - G2 * self._levy(P) + r * G1                   # (14)
            Xn = np.where(choose[:, None], X3, X4)
        return self.clip(Xn)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X, F.copy()
            return
        better = F < self.F
        np.copyto(self.X, X, where=better[:, None])
        np.copyto(self.F, F, where=better)
