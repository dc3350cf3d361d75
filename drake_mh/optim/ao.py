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

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import greedy_replace
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
        self._no_box = np.empty((0, self.dim))

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, P, D = self.config, self.pop_size, self.dim
        t, T = self.nit, self.T
        early = t <= 2.0 * T / 3.0
        R = self.rng.random((P, 5))
        n_levy = int(np.count_nonzero(R[:, 0] > 0.5))     # agents on eq. (5) or (14)
        Z = self.rng.standard_normal((2, n_levy, D))
        B = self._no_box if early else self.rng.random((P - n_levy, D))
        return _move(self.X, self.best_x, R, Z, B, t, T, early, c.alpha, c.delta, c.s * self.sigma,
                     1.0 / c.beta, self.spiral, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X, F.copy()
            return
        greedy_replace(self.X, self.F, X, F, False)


@numba.njit(cache=True)
def _move(X, Xb, R, Z, B, t, T, early, alpha, delta, s_sigma, inv_beta, spiral, lower, upper):
    """Eqs. (3), (5), (13), (14) for every agent, then clip onto the box.

    ``R (P, 5)`` per agent: the strategy test (``<= 0.5``: eq. (3) / (13)), ``rand`` of
    the equations, QF's and G1's draws (eqs. (15)-(16)) and the random agent X_R
    (``floor(u P)``). The agents with ``R[i, 0] > 0.5`` take, in order, the rows of
    ``Z (2, n_levy, D)``: Levy(D) = ``s sigma Z0 / |Z1|^(1/beta)`` (Mantegna, eqs. (6)-(7);
    ``s_sigma = s sigma``, ``inv_beta = 1 / beta``). Late (``early`` false), the other
    agents take, in order, the rows of ``B (P - n_levy, D)``: uniforms for eq. (13)'s
    random box point. Returns the new positions ``(P, D)``.
    """
    P, D = X.shape
    tau = min(t / T, 1.0)
    XM = np.zeros(D)
    for i in range(P):
        for d in range(D):
            XM[d] += X[i, d]
    XM /= P
    G2 = 2.0 * (1.0 - tau)                                                      # (17)
    Xn = np.empty((P, D))
    n_levy, n_box = 0, 0
    for i in range(P):
        r = R[i, 1]
        levy = R[i, 0] > 0.5
        if early and not levy:                                                  # (3)
            for d in range(D):
                Xn[i, d] = Xb[d] * (1.0 - tau) + (XM[d] - Xb[d] * r)
        elif early:                                                             # (5)
            k = min(int(R[i, 4] * P), P - 1)
            for d in range(D):
                L = s_sigma * Z[0, n_levy, d] / abs(Z[1, n_levy, d]) ** inv_beta
                Xn[i, d] = Xb[d] * L + X[k, d] + spiral[d] * r
            n_levy += 1
        elif not levy:                                                          # (13)
            for d in range(D):
                box = lower[d] + (upper[d] - lower[d]) * B[n_box, d]
                Xn[i, d] = (Xb[d] - XM[d]) * alpha - r + box * delta
            n_box += 1
        else:                                                                   # (14)
            QF = float(t) ** ((2.0 * R[i, 2] - 1.0) / (1.0 - T) ** 2)           # (15)
            G1 = 2.0 * R[i, 3] - 1.0                                            # (16)
            for d in range(D):
                L = s_sigma * Z[0, n_levy, d] / abs(Z[1, n_levy, d]) ** inv_beta
                Xn[i, d] = QF * Xb[d] - G1 * X[i, d] * r - G2 * L + r * G1
            n_levy += 1
        for d in range(D):
            Xn[i, d] = min(max(Xn[i, d], lower[d]), upper[d])
    return Xn
