"""e3GSA as defined in drake_mh: GSA with enhanced exploration and exploitation.

The framework paper's e3GSA (Sheik Masthan, Kanagaraj & Yu, "Gravitation search-based
hybrid algorithm for solving inverse kinematics of an n-link redundant manipulator",
J. Computational Design and Engineering 10(5):2019-2035, 2023) is not available offline,
so its exact operators are unknown here. This module defines a *documented* GSA hybrid
with the same intent; it is **not** a reproduction of the published algorithm.

Definition (t/T = used budget fraction; everything else as in :mod:`drake_mh.optim.gsa`):

1. Gravitational acceleration ``a_i`` of GSA (Rashedi et al. 2009, eqs. (7)-(10)), with G0,
   alpha and the shrinking Kbest of GSA.
2. Enhanced exploitation - memory of the global best, as in PSOGSA (Mirjalili & Hashim,
   "A new hybrid PSOGSA algorithm for function optimization", ICCIA 2010, eq. (9))::

       v_i <- w v_i + c1 r1 a_i + c2 r2 (g - x_i),   w ~ U(0, 1) per agent and dimension,
                                                     r1, r2 ~ U(0, 1),  c1 = 0.5, c2 = 1.5
       x_i <- x_i + v_i

   GSA alone has no memory of the best position; the social term pulls the swarm to it.
3. Enhanced exploration - differential jumps for the worst agents: every generation the
   worst ``ceil(p_explore (1 - t/T) N)`` agents are replaced by DE/rand/1 points
   (Storn & Price 1997) ``x_r1 + F (x_r2 - x_r3)`` with F = 0.5 and distinct random
   ``r1, r2, r3``; their velocity is reset to 0. Differences of population members are
   translation-invariant, so this adds no pull towards the box centre (unlike opposition-
   based learning, a common exploration operator that is centre-biased).

Bound handling: out-of-box components are re-drawn uniformly inside the box (as GSA).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import distinct_indices
from drake_mh.optim.gsa import _EPS, GSA, _acceleration_kernel


@dataclass(frozen=True)
class E3GSAConfig:
    """e3GSA (drake_mh definition) hyper-parameters.

    Attributes:
        G0: initial gravitational constant (100, GSA).
        alpha: decay rate of G (20, GSA).
        final_fraction: final Kbest fraction (0.02, GSA).
        c1: weight of the gravitational acceleration (0.5, PSOGSA).
        c2: weight of the pull to the global best (1.5, PSOGSA).
        p_explore: fraction of worst agents replaced by DE/rand/1 jumps at t = 0 (0.2),
            decreasing linearly to 0.
        F: DE scale factor of the jumps (0.5, Storn & Price 1997).
    """

    G0: float = 100.0
    alpha: float = 20.0
    final_fraction: float = 0.02
    c1: float = 0.5
    c2: float = 1.5
    p_explore: float = 0.2
    F: float = 0.5

    def __post_init__(self):
        if self.G0 <= 0 or self.alpha < 0:
            raise InvalidArgument("e3gsa: G0 must be > 0 and alpha >= 0")
        if not (0 < self.final_fraction <= 1):
            raise InvalidArgument("e3gsa: final_fraction must be in (0, 1]")
        if not (0 <= self.p_explore <= 1):
            raise InvalidArgument("e3gsa: p_explore must be in [0, 1]")


class E3GSA(GSA):
    """GSA + PSOGSA-style global-best memory + DE/rand/1 jumps of the worst agents."""

    name = "e3gsa"
    Config = E3GSAConfig
    min_pop_size = 4

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        c, N, D = self.config, self.pop_size, self.dim
        G, k = self.schedule()
        n_jump = math.ceil(c.p_explore * (1.0 - self.progress()) * N)
        n_w, n_r = N * k, 4 * N * D
        U = self.rng.random(n_w + n_r + 3 * n_jump)
        a = _acceleration_kernel(self.X, self.F, U[:n_w].reshape(k, N), G, _EPS)
        donors = distinct_indices(U[n_w + n_r:].reshape(n_jump, 3), N, False)   # three distinct agents
        return _move(self.X, self.V, self.F, a, self.best_x, U[n_w:n_w + n_r].reshape(4, N, D),
                     donors, c.c1, c.c2, c.F, self.lower, self.upper)


@numba.njit(cache=True)
def _move(X, V, FX, a, g, R, donors, c1, c2, F, lower, upper):
    """Steps 2-3 and the re-draw of out-of-box components; ``V`` is updated in place.

    ``R (4, N, D)``: w, r1, r2 of step 2, then the uniforms of the re-draws. ``donors
    (n_jump, 3)``: r1, r2, r3 of the DE/rand/1 jump of each of the ``n_jump`` worst agents
    (by ``FX``, stable order: among equal values the higher index counts as worse).
    Returns the new positions ``(N, D)``.
    """
    N, D = X.shape
    Xn = np.empty((N, D))
    for i in range(N):
        for d in range(D):
            v = R[0, i, d] * V[i, d] + c1 * R[1, i, d] * a[i, d] + c2 * R[2, i, d] * (g[d] - X[i, d])
            V[i, d] = v
            Xn[i, d] = X[i, d] + v
    n_jump = donors.shape[0]
    if n_jump > 0:
        worst = np.argsort(FX, kind="mergesort")[N - n_jump:]
        for m in range(n_jump):
            i = worst[m]
            p, q, r = donors[m, 0], donors[m, 1], donors[m, 2]
            for d in range(D):
                Xn[i, d] = X[p, d] + F * (X[q, d] - X[r, d])
                V[i, d] = 0.0
    for i in range(N):
        for d in range(D):
            if Xn[i, d] < lower[d] or Xn[i, d] > upper[d]:
                Xn[i, d] = lower[d] + R[3, i, d] * (upper[d] - lower[d])
    return Xn
