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

import numpy as np

from drake_mh.errors import InvalidArgument
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
        Xc, V = self.Xc, self.V
        R[0] *= c.c1
        R[0] *= self.Pb - Xc
        R[1] *= c.c2
        R[1] *= self.best_x - Xc
        V *= w
        V += R[0]
        V += R[1]
        np.maximum(V, -self.vmax, out=V)
        np.minimum(V, self.vmax, out=V)
        X = Xc + V
        out = (X < self.lower) | (X > self.upper)
        self.clip(X)
        np.copyto(V, 0.0, where=out)                 # absorbing walls
        return X

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.Xc is None:
            self.Xc, self.Pb, self.Pf = X, X.copy(), F.copy()
            return
        self.Xc = X
        better = F < self.Pf
        np.copyto(self.Pb, X, where=better[:, None])
        np.copyto(self.Pf, F, where=better)

    def population(self):
        """Personal bests ``(P, D)`` and their values ``(P,)``."""
        if self.Xc is None:
            return None, None
        return self.Pb.copy(), self.Pf.copy()
