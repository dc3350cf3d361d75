"""Single-configuration kernels of the compiled LM restart loop (:func:`drake_mh.ik.lm.lm_run`).

* :func:`fk_jacobian_one`: FK and geometric Jacobian of one configuration from the compiled
  chain of :class:`drake_mh.kinematics.BatchKinematics`, without allocation;
* :func:`uniform_hash`: the counter-based generator of the restarts' starting points.

Both are inlined into the loop (numba ``inline="always"``).
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh.kinematics.kernels import fk_jacobian_one  # shared with Robot.fk / Robot.jacobian

__all__ = ["fk_jacobian_one", "uniform_hash"]


_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


@numba.njit(cache=True, inline="always")
def uniform_hash(seed, n):
    """A uniform number in [0, 1) from ``(seed, n)``: SplitMix64's output function (Steele,
    Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014) applied to
    ``seed + (n + 1) γ``, i.e. draw ``n`` of the SplitMix64 stream started at ``seed``.

    Counter-based, so a start depends on the seed and its index only (no state to carry
    between compiled calls, no numpy ``Generator`` to build per solve: 7 µs). ``seed`` is a
    ``uint64``, ``n`` an integer >= 0.
    """
    z = seed + (np.uint64(n) + np.uint64(1)) * _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    z = z ^ (z >> np.uint64(31))
    return np.float64(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)
