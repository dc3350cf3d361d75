"""Pure random search, the floor every optimizer must beat.

Source: uniform sampling of the box (Brooks, "A discussion of random methods for seeking
maxima", Operations Research 6(2):244-251, 1958). Batches of ``pop_size`` (default 100)
i.i.d. uniform points; ``x0`` rows are evaluated first. Always inside the box.
"""

from __future__ import annotations

import numpy as np

from drake_mh.optim.base import Optimizer


class RandomSearch(Optimizer):
    """Uniform random sampling in batches of ``pop_size``."""

    name = "random"
    min_pop_size = 1

    @classmethod
    def default_pop_size(cls, dim: int) -> int:
        return 100

    def _start(self) -> None:
        self._first = True

    def _ask(self) -> np.ndarray:
        if self._first:
            self._first = False
            return self.initial_population()
        return self.lower + self.rng.random((self.pop_size, self.dim)) * self.width

    def _tell(self, X: np.ndarray, F: np.ndarray) -> None:
        pass
