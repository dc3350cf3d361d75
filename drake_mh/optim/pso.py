"""Particle swarm optimization with inertia weight.

Sources:
    Kennedy & Eberhart, "Particle swarm optimization", Proc. ICNN 1995 (velocity/position
    update, Vmax); Shi & Eberhart, "A modified particle swarm optimizer", IEEE ICEC 1998
    (inertia weight w); Shi & Eberhart, "Empirical study of particle swarm optimization",
    CEC 1999 (w decreasing linearly from 0.9 to 0.4).

Update (per particle i, dimension d; r1, r2 ~ U(0, 1) drawn per particle *and* dimension)::

    v <- w(t) v + c1 r1 (pbest - x) + c2 r2 (gbest - x)        (Shi & Eberhart 1998, eq. 2)
    v <- clip(v, -vmax, vmax)                                   (Kennedy & Eberhart 1995)
    x <- x + v

Bound handling: positions are clipped onto the box and the velocity component that left
the box is set to zero ("absorbing walls"); the papers leave this open.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import greedy_replace
from drake_mh.optim.base import Optimizer


@dataclass(frozen=True)
class PSOConfig:
    """PSO hyper-parameters.

    Attributes:
        w_start: inertia weight at t = 0 (0.9, Shi & Eberhart 1999).
        w_end: inertia weight at the end of the budget (0.4, Shi & Eberhart 1999).
        c1: cognitive acceleration (2.0, Kennedy & Eberhart 1995; Shi & Eberhart 1998).
        c2: social acceleration (2.0, same sources).
        vmax: velocity clamp as a fraction of the box width per dimension (0.2; Vmax is
            problem-dependent in the papers, 10-20 % of the range is the usual choice).
    """

    w_start: float = 0.9
    w_end: float = 0.4
    c1: float = 2.0
    c2: float = 2.0
    vmax: float = 0.2

    def __post_init__(self):
        if not (self.vmax > 0):
            raise InvalidArgument(f"pso: vmax must be > 0 (fraction of the box width); got {self.vmax}")
        if self.c1 < 0 or self.c2 < 0:
            raise InvalidArgument("pso: c1 and c2 must be >= 0")


class PSO(Optimizer):
    """Inertia-weight PSO (Shi & Eberhart 1998), default swarm of 40 particles."""

    name = "pso"
    Config = PSOConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 40

    def _start(self) -> None:
        self.Xc = None  # current positions (P, D); None until the initial swarm is told
        self.V = (self.rng.random((self.pop_size, self.dim)) - 0.5) * (self.config.vmax * self.width)
        self.vmax = self.config.vmax * self.width

    def _ask(self) -> np.ndarray:
        if self.Xc is None:
            return self.initial_population()
        c = self.config
        w = c.w_start + (c.w_end - c.w_start) * self.progress()
        R = self.rng.random((2, self.pop_size, self.dim))
        return _step(self.Xc, self.V, self.Pb, self.best_x, R, w, c.c1, c.c2, self.vmax,
                     self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.Xc is None:
            self.Xc, self.Pb, self.Pf = X, X.copy(), F.copy()
            return
        self.Xc = X
        greedy_replace(self.Pb, self.Pf, X, F, False)

    def population(self):
        """Personal bests ``(P, D)`` and their values ``(P,)``."""
        if self.Xc is None:
            return None, None
        return self.Pb.copy(), self.Pf.copy()


@numba.njit(cache=True)
def _step(X, V, Pb, g, R, w, c1, c2, vmax, lower, upper):
    """One PSO move: the velocity update, the Vmax clamp and the absorbing walls.

    ``V (P, D)`` is updated in place; returns the new positions. ``R (2, P, D)`` holds
    r1 and r2.
    """
    P, D = X.shape
    Xn = np.empty((P, D))
    for i in range(P):
        for d in range(D):
            v = (w * V[i, d] + c1 * R[0, i, d] * (Pb[i, d] - X[i, d])
                 + c2 * R[1, i, d] * (g[d] - X[i, d]))
            v = min(max(v, -vmax[d]), vmax[d])
            x = X[i, d] + v
            if x < lower[d]:
                x, v = lower[d], 0.0
            elif x > upper[d]:
                x, v = upper[d], 0.0
            V[i, d] = v
            Xn[i, d] = x
    return Xn
