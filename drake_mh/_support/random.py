"""The one random generator of the compiled kernels: SplitMix64.

Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014: a 64-bit
state advanced by the golden-ratio increment ``γ = 0x9E3779B97F4A7C15``, each state mixed by a
variant of MurmurHash3's finalizer. Draw ``n`` (from 0) of the stream started at ``seed`` is
``mix64(seed + (n + 1) γ)``, so it can be used two ways that give the same numbers:

* with a state (:func:`next_u64`, :func:`uniform`, :func:`below`): ``state`` a ``(1,)`` uint64
  array holding the last state, advanced in place (the planners' search loops);
* counter-based (:func:`uniform_at`): draw ``n`` directly from ``(seed, n)``, no state to carry
  between compiled calls (the IK restarts' starting points).

Every function is inlined where it is called (numba ``inline="always"``).
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["GOLDEN", "mix64", "next_u64", "uniform", "below", "uniform_at"]

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
"""The stream's increment γ (2^64 / φ, odd)."""
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_UNIT = 1.0 / 9007199254740992.0  # 2^-53


@numba.njit(cache=True, inline="always")
def mix64(z):
    """SplitMix64's output function of one uint64 state."""
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@numba.njit(cache=True, inline="always")
def next_u64(state):
    """The next 64 random bits; ``state`` a ``(1,)`` uint64 array, advanced in place."""
    z = state[0] + GOLDEN
    state[0] = z
    return mix64(z)


@numba.njit(cache=True, inline="always")
def uniform(state):
    """Uniform in [0, 1) with 53 random bits (the next draw of ``state``)."""
    return np.float64(next_u64(state) >> _S11) * _UNIT


@numba.njit(cache=True, inline="always")
def below(state, n):
    """Uniform integer in [0, n) (the next draw of ``state``)."""
    return min(int(uniform(state) * n), n - 1)


@numba.njit(cache=True, inline="always")
def uniform_at(seed, n):
    """Draw ``n`` (an integer >= 0) of the stream started at ``seed`` (a uint64), uniform in
    [0, 1): the value :func:`uniform` returns at its ``n + 1``-th call from ``state = [seed]``."""
    return np.float64(mix64(seed + (np.uint64(n) + np.uint64(1)) * GOLDEN) >> _S11) * _UNIT
