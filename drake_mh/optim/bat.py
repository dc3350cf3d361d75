"""Bat algorithm.

Source: X.-S. Yang, "A new metaheuristic bat-inspired algorithm", Nature Inspired
Cooperative Strategies for Optimization (NICSO 2010), SCI 284, pp. 65-74.

Equations (numbers of Yang 2010)::

    f_i = f_min + (f_max - f_min) beta,   beta ~ U(0, 1)                       (2)
    v_i <- v_i + (x_i - x*) f_i                                                 (3)
    x_i <- x_i + v_i                                                            (4)
    if rand > r_i:  x_new = x* + eps <A>,  eps ~ U(-1, 1)^D  (local walk)        (5)
    accept x_new if rand < A_i and f(x_new) < f(x_i); then
        A_i <- alpha A_i,   r_i <- r_i0 (1 - exp(-gamma t))                      (6)

Choices, and defects of the popular demo code that are *not* copied:

* ``beta`` is "a random vector": drawn per bat and per dimension (``(P, D)``), so each
  coordinate gets its own frequency (``beta_per_dimension=False`` draws one per bat).
* The frequency is ``f_min + (f_max - f_min) beta`` - the demo's
  ``Qmin + (Qmin - Qmax) rand`` sign error (a negative frequency) is not reproduced.
* Loudness ``A_i`` and pulse rate ``r_i`` are updated per bat by eq. (6) whenever a move
  is accepted (the demo never updates them). ``t`` counts generations.
* A move is accepted when it improves the bat's *own* value (Yang's reference code); the
  paper's pseudocode compares with the global best f(x*), which rejects almost every move.
* Eq. (5) has an absolute step ``eps <A>``; since the box may be ``[-100, 100]`` or
  ``[-1, 1]``, the step is scaled by ``local_scale`` times the box width.
* Velocities are clamped to the box width (no clamp in the paper; avoids overflow).

Bound handling: clip onto the box (the paper is silent; Yang's code clips).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class BATConfig:
    """Bat-algorithm hyper-parameters (Yang 2010 Sect. 3-4).

    Attributes:
        f_min: minimum frequency (0).
        f_max: maximum frequency (2; the paper uses a range comparable to the domain scale,
            the update (3) multiplies distances, so 0..2 is scale-free).
        loudness: initial loudness A_0 (drawn U(1, 2) per bat when ``None``, paper: A0 in [1, 2]).
        pulse_rate: initial pulse emission rate r_0 (drawn U(0, 1) per bat when ``None``).
        alpha: loudness decay (0.9, paper).
        gamma: pulse-rate growth (0.9, paper).
        local_scale: eq. (5) step as a fraction of the box width (0.01).
        beta_per_dimension: draw beta per dimension (True) or one per bat (False).
    """

    f_min: float = 0.0
    f_max: float = 2.0
    loudness: float | None = None
    pulse_rate: float | None = None
    alpha: float = 0.9
    gamma: float = 0.9
    local_scale: float = 0.01
    beta_per_dimension: bool = True

    def __post_init__(self):
        if not (0 < self.alpha < 1):
            raise InvalidArgument(f"bat: alpha must be in (0, 1); got {self.alpha}")
        if self.gamma <= 0:
            raise InvalidArgument(f"bat: gamma must be > 0; got {self.gamma}")
        if self.f_max < self.f_min:
            raise InvalidArgument("bat: f_max must be >= f_min")


class BAT(Optimizer):
    """Bat algorithm (Yang 2010), default 40 bats."""

    name = "bat"
    Config = BATConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 40

    def _start(self) -> None:
        c, P = self.config, self.pop_size
        self.X = None
        self.V = np.zeros((P, self.dim))
        self.A = np.full(P, c.loudness) if c.loudness is not None else 1.0 + self.rng.random(P)
        self.r0 = np.full(P, c.pulse_rate) if c.pulse_rate is not None else self.rng.random(P)
        self.r = self.r0.copy()
        self._t = 0

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, P, D = self.config, self.pop_size, self.dim
        R = self.rng.random((P, D + 2 + (D if c.beta_per_dimension else 1)))
        beta = R[:, D + 2:]
        freq = c.f_min + (c.f_max - c.f_min) * beta                         # eq. (2)
        V = self.V + (self.X - self.best_x) * freq                           # eq. (3)
        np.clip(V, -self.width, self.width, out=V)
        self.V = V
        Xn = self.X + V                                                      # eq. (4)
        local = R[:, D] > self.r                                             # eq. (5)
        if local.any():
            eps = 2.0 * R[local, :D] - 1.0
            Xn[local] = self.best_x + eps * (c.local_scale * self.A.mean()) * self.width
        self._accept_draw = R[:, D + 1]
        return self.clip(Xn)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        self._t += 1
        acc = (F < self.F) & (self._accept_draw < self.A)                   # eq. (6)
        np.copyto(self.X, X, where=acc[:, None])
        np.copyto(self.F, F, where=acc)
        self.A[acc] *= self.config.alpha
        self.r[acc] = self.r0[acc] * (1.0 - np.exp(-self.config.gamma * self._t))
