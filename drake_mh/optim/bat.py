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

import math
from dataclasses import dataclass

import numba
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
        self.A = np.full(P, float(c.loudness)) if c.loudness is not None else 1.0 + self.rng.random(P)
        self.r0 = np.full(P, float(c.pulse_rate)) if c.pulse_rate is not None else self.rng.random(P)
        self.r = self.r0.copy()
        self._t = 0

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, P, D = self.config, self.pop_size, self.dim
        R = self.rng.random((P, D + 2 + (D if c.beta_per_dimension else 1)))
        self._accept_draw = R[:, D + 1]
        return _move(self.X, self.V, self.best_x, R, c.f_min, c.f_max, self.r, self.A,
                     c.local_scale, self.lower, self.upper, self.width)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        self._t += 1
        r_t = 1.0 - math.exp(-self.config.gamma * self._t)
        _accept(self.X, self.F, X, F, self._accept_draw, self.A, self.r, self.r0,
                self.config.alpha, r_t)


@numba.njit(cache=True)
def _move(X, V, g, R, f_min, f_max, r, A, local_scale, lower, upper, width):
    """Eqs. (2)-(5) for every bat, then clip onto the box; ``V`` is updated in place.

    ``R (P, D + 2 + nb)``: columns ``0..D-1`` the local-walk ``eps`` (as ``2 u - 1``),
    ``D`` the pulse test of eq. (5), ``D + 1`` the acceptance draw (used by
    :func:`_accept`), ``D + 2..`` beta (``nb = D`` per dimension, or 1 per bat).
    Returns the new positions ``(P, D)``.
    """
    P, D = X.shape
    per_dim = R.shape[1] - D - 2 == D
    step = local_scale * A.mean()
    Xn = np.empty((P, D))
    for i in range(P):
        local = R[i, D] > r[i]                                          # eq. (5)
        for d in range(D):
            beta = R[i, D + 2 + d] if per_dim else R[i, D + 2]
            freq = f_min + (f_max - f_min) * beta                          # eq. (2)
            v = V[i, d] + (X[i, d] - g[d]) * freq                          # eq. (3)
            v = min(max(v, -width[d]), width[d])
            V[i, d] = v
            if local:
                x = g[d] + (2.0 * R[i, d] - 1.0) * step * width[d]
            else:
                x = X[i, d] + v                                            # eq. (4)
            Xn[i, d] = min(max(x, lower[d]), upper[d])
    return Xn


@numba.njit(cache=True)
def _accept(X, F, Xn, Fn, draw, A, r, r0, alpha, r_t):
    """Eq. (6) in place: bat ``i`` moves to ``Xn[i]`` if ``Fn[i] < F[i]`` and
    ``draw[i] < A[i]``; then ``A_i <- alpha A_i`` and ``r_i <- r0_i r_t`` with
    ``r_t = 1 - exp(-gamma t)``."""
    P, D = X.shape
    for i in range(P):
        if Fn[i] < F[i] and draw[i] < A[i]:
            for d in range(D):
                X[i, d] = Xn[i, d]
            F[i] = Fn[i]
            A[i] *= alpha
            r[i] = r0[i] * r_t
