"""Artificial rabbits optimization, and the ESM paper's AMNN arrangement of it.

Sources: L. Wang, Q. Cao, Z. Zhang, S. Mirjalili, W. Zhao, "Artificial rabbits
optimization: A new bio-inspired meta-heuristic algorithm for solving engineering
optimization problems", Engineering Applications of Artificial Intelligence 114:105082,
2022 ("ARO"); eqs. (12)-(21) of the ESM paper ("AMNN": the same agent update arranged as
L layers of P agent neurons; layer l = generation t, L = T).

Per rabbit i and generation t of T (r* ~ U(0, 1) scalars per rabbit)::

    A = 4 (1 - t/T) ln(1/r1)                                    energy (ARO 15, ESM 12)
    c = mask of ceil(r2 D) random dimensions                     (ARO 4, ESM 13)
    R = (e - exp(((t - 1)/T)^2)) sin(2 pi r3) c                  (ARO 2-3, ESM 14)
    A > 1, detour foraging towards a random other rabbit j:
        aro : v = x_j + R o (x_i - x_j) + round(0.5 (0.05 + r4)) n1,  n1 ~ N(0, 1)   (ARO 1)
        amnn: v = x_i + R o (x_j - x_i)                                            (ESM 15)
    A <= 1, random hiding in a burrow near x_i (g = one random dimension):
        b = x_i + H g o x_i,  H = (T - t + 1)/T n2                   (ARO 8, 13; ESM 16-17)
        v = x_i + R o (r5 b - x_i)                                   (ARO 11, ESM 18)
        n2 ~ N(0, 1) for ``aro`` (the authors' code), U(0, 1) for ``amnn`` (ESM text)
    greedy: x_i <- v if f(v) < f(x_i)                                (ARO 16, ESM 20)

Bound handling: ``aro`` re-draws out-of-box components uniformly (authors' code);
``amnn`` projects onto the box (ESM eq. (19), the velocity-feasibility test of eq. (19)
belongs to the problem, not the optimizer).

Warm start: ``x0`` of shape ``(K, D)``, ``K <= pop_size``, replaces the first K rabbits of
the initial population; passing the previous control step's population
(``OptimizeResult.population``) continues the search, as the ESM control loop does.

Note the hiding move scales a coordinate by itself (``H g o x_i``) and pulls towards
``r5 b`` (a shrunk copy of x_i): both are attracted by the origin, a source of centre bias.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.population import greedy_replace
from drake_mh.optim.base import Optimizer

VARIANTS = ("aro", "amnn")


@dataclass(frozen=True)
class AROConfig:
    """ARO hyper-parameters.

    Attributes:
        variant: ``"aro"`` (Wang et al. 2022 and their code) or ``"amnn"`` (ESM eqs. 12-21).
    """

    variant: str = "aro"

    def __post_init__(self):
        if self.variant not in VARIANTS:
            raise InvalidArgument(f"aro: variant must be one of {VARIANTS}; got {self.variant!r}")


class ARO(Optimizer):
    """Artificial rabbits optimization (Wang et al. 2022), default 50 rabbits."""

    name = "aro"
    Config = AROConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 50

    def _start(self) -> None:
        self.X = None
        self.T = max(1, math.ceil(self.budget / self.pop_size) - 1)
        self.amnn = self.config.variant == "amnn"
        self._no_normals = np.empty((2, 0))

    def _ask(self) -> np.ndarray:
        if self.X is None:
            return self.initial_population()
        P, D = self.pop_size, self.dim
        t, T = min(self.nit, self.T), self.T
        U = self.rng.random((P, 8 + (D if self.amnn else 2 * D)))
        N = self._no_normals if self.amnn else self.rng.standard_normal((2, P))
        return rabbit_moves(self.X, U, N, t, T, self.amnn, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        if self.X is None:
            self.X, self.F = X.copy(), F.copy()
            return
        greedy_replace(self.X, self.F, X, F, False)                                 # ESM (20)


@numba.njit(cache=True)
def rabbit_moves(X, U, N, t, T, amnn, lower, upper):
    """One generation of candidate moves (detour or hiding) for every rabbit, then the
    variant's bound handling. Returns the candidates ``(P, D)``.

    ``U (P, 8 + D)`` for ``amnn``, ``(P, 8 + 2 D)`` for ``aro``; per rabbit, the columns
    are r1 (energy A), r2 (size of the mask c), r3 (angle of R), r4 (the jump, ``aro``),
    n2 (``amnn``), r5, the other rabbit j (``floor(u (P - 1))``, skipping i), the burrow
    dimension g (``floor(u D)``), ``D`` draws of a partial Fisher-Yates shuffle that picks
    the ``ceil(r2 D)`` dimensions of c, and (``aro``) ``D`` uniforms re-drawing out-of-box
    components. ``N (2, P)`` (``aro`` only): n1 and n2 ~ N(0, 1).
    """
    P, D = X.shape
    Lw0 = math.e - math.exp(((t - 1) / T) ** 2)
    Hs = (T - t + 1) / T
    Xn = np.empty((P, D))
    R = np.empty(D)
    perm = np.empty(D, dtype=np.int64)
    for i in range(P):
        A = 4.0 * (1.0 - t / T) * math.log(1.0 / max(U[i, 0], 1e-300))     # ARO (15)
        n_dims = int(math.ceil(U[i, 1] * D))                                # ARO (4)
        for d in range(D):
            perm[d] = d
            R[d] = 0.0
        Lw = Lw0 * math.sin(2.0 * math.pi * U[i, 2])                         # ARO (2)-(3)
        for m in range(n_dims):
            q = m + min(int(U[i, 8 + m] * (D - m)), D - m - 1)
            perm[m], perm[q] = perm[q], perm[m]
            R[perm[m]] = Lw
        if A > 1.0:                                                           # detour
            j = (i + 1 + min(int(U[i, 6] * (P - 1)), P - 2)) % P
            if amnn:
                for d in range(D):
                    Xn[i, d] = X[i, d] + R[d] * (X[j, d] - X[i, d])            # ESM (15)
            else:
                jump = round(0.5 * (0.05 + U[i, 3])) * N[0, i]
                for d in range(D):
                    Xn[i, d] = X[j, d] + R[d] * (X[i, d] - X[j, d]) + jump     # ARO (1)
        else:                                                                 # hiding
            n2 = U[i, 4] if amnn else N[1, i]
            H = Hs * n2                                                       # ARO (8)
            g = min(int(U[i, 7] * D), D - 1)
            r5 = U[i, 5]
            for d in range(D):
                b = X[i, d] + H * X[i, d] if d == g else X[i, d]              # ARO (13)
                Xn[i, d] = X[i, d] + R[d] * (r5 * b - X[i, d])                # ARO (11)
        for d in range(D):
            x = Xn[i, d]
            if x < lower[d] or x > upper[d]:
                if amnn:
                    x = min(max(x, lower[d]), upper[d])                       # ESM (19)
                else:
                    x = lower[d] + U[i, 8 + D + d] * (upper[d] - lower[d])    # re-draw
            Xn[i, d] = x
    return Xn
