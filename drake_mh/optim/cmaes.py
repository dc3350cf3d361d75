"""CMA-ES reference baseline through the ``cma`` package (pycma), ask/tell.

Source: N. Hansen, "The CMA Evolution Strategy: A Tutorial", arXiv:1604.00772 (2016);
N. Hansen & A. Ostermeier, Evolutionary Computation 9(2):159-195, 2001. Implementation:
``cma.CMAEvolutionStrategy`` (pycma) with its default parameters.

How it is wrapped:

* The search runs in normalized coordinates ``y = (x - lower) / (upper - lower)`` in
  ``[0, 1]^D`` (CMA-ES wants comparable scales per coordinate), initial step
  ``sigma0 = 0.3`` (pycma advises about a quarter to a third of the range).
* The initial mean is ``x0[0]`` when given (all ``x0`` rows are injected into the first
  generation with ``inject(force=True)``), else a *uniformly random point of the box*,
  not the box centre, so that CMA-ES gets no centre advantage.
* Population size ``lambda = 4 + floor(3 ln D)`` (pycma's default) unless ``pop_size`` is given.
* Randomness: pycma's normal draws go through ``options['randn']`` bound to this run's
  ``numpy.random.Generator``; pycma's global-seed option is disabled (NaN), so runs are
  bit-reproducible and never touch ``numpy.random``'s global state.
* Exact budget: the last generation is truncated by the base class (see
  :mod:`drake_mh.optim.base`); pycma never sees a partial generation.
* When pycma's own termination criteria fire (``tolfun``, ``tolx``, ...), the strategy is
  restarted from a new uniformly random mean with the same ``lambda`` (independent
  restarts), so the budget is always used.

D = 1 is refused (pycma 4.x fails on it with an explicit population size).

Bound handling: pycma's own ``BoxConstraintsLinQuadTransformation`` (the map behind its
``BoundTransform``: identity inside ``[0.05, 0.95]``, quadratic towards each bound,
mirrored/periodic outside), applied by us to the whole population in one call. pycma runs
unbounded on the genotype, with ``maxstd = 1/3`` of the range as its bounded mode would
set. Measured reason: pycma's bounded mode applies the transform one individual at a time
in Python, which made the mapping cost more than the whole CMA update (D = 30, lambda =
14: 1.05 ms per generation bounded vs 0.48 ms unbounded, same machine). The evaluated
points are always inside the box; injected ``x0`` points go in through the transform's
inverse, so they are evaluated exactly where they are.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.optim.base import Optimizer

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CMAESConfig:
    """CMA-ES wrapper settings.

    Attributes:
        sigma0: initial step size in normalized coordinates (0.3 of the box width).
        restarts: restart when pycma's termination criteria fire (True).
    """

    sigma0: float = 0.3
    restarts: bool = True

    def __post_init__(self):
        if not (self.sigma0 > 0):
            raise InvalidArgument(f"cmaes: sigma0 must be > 0; got {self.sigma0}")


class CMAES(Optimizer):
    """pycma CMA-ES with exact budget and seeded Generator."""

    name = "cmaes"
    Config = CMAESConfig
    min_pop_size = 2

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 4 + int(math.floor(3 * math.log(dim))) if dim > 1 else 4

    def _start(self) -> None:
        if self.dim < 2:
            raise InvalidArgument(
                "cmaes needs D >= 2 (pycma 4.x fails on 1-D problems with an explicit population "
                "size); use 'de' or 'pso' for a single variable"
            )
        import cma  # local import: pycma takes ~0.2 s to import

        from cma.transformations import BoxConstraintsLinQuadTransformation

        self._cma = cma
        self._to_box = BoxConstraintsLinQuadTransformation([[0.0, 1.0]])
        self.restarts = 0
        if self.x0 is not None:
            mean = self._to_box.inverse((self.x0[0] - self.lower) / self.width)
        else:
            mean = self.rng.random(self.dim)
        self._new_es(mean)
        if self.x0 is not None:
            Y0 = (self.x0[: self.pop_size] - self.lower) / self.width
            self.es.inject([self._to_box.inverse(y) for y in Y0], force=True)

    def _new_es(self, mean: np.ndarray) -> None:
        rng = self.rng
        opts = {
            "popsize": self.pop_size,
            "maxstd": 1.0 / 3.0,
            "seed": float("nan"),
            "randn": lambda *shape: rng.standard_normal(shape),
            "verbose": -9,
            "maxfevals": np.inf,
            "maxiter": np.inf,
        }
        self.es = self._cma.CMAEvolutionStrategy([float(m) for m in mean], self.config.sigma0, opts)

    def _ask(self) -> np.ndarray:
        G = np.asarray(self.es.ask(), dtype=float)      # genotypes, unbounded
        self._G = G
        Y = self._to_box(G.ravel(), copy=True).reshape(G.shape)   # all rows at once
        return np.clip(self.lower + Y * self.width, self.lower, self.upper)

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        Ft = np.where(np.isfinite(F), F, np.finfo(float).max)
        self.es.tell(list(self._G), list(Ft))
        if self.config.restarts and self.es.stop():
            self.restarts += 1
            logger.debug("cmaes restart %d after %s", self.restarts, dict(self.es.stop()))
            self._new_es(self.rng.random(self.dim))
