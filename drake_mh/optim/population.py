"""Compiled helpers shared by several optimizers (greedy selection, distinct random indices).

Why compiled: at the population sizes of this library (P = 20-100, D = 2-30) a numpy
expression costs a microsecond or more of call overhead whatever its size, so an ask/tell
step written as ten numpy expressions costs tens of microseconds; a compiled loop over the
population costs a few. Each optimizer keeps its own step kernel in its module; what
several of them share is here.

Random numbers are *not* drawn inside kernels: passing a ``numpy.random.Generator`` into a
numba function costs ~9 us of unboxing per call, more than the work. Callers draw the
uniforms they need with one ``rng.random(...)`` call and pass the array in, so every run
stays deterministic per seed.

These kernels are called from Python only (never from another module's kernel): numba's
on-disk cache does not notice when a function in another file changes.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["distinct_indices", "greedy_replace"]


@numba.njit(cache=True)
def greedy_replace(X, F, Xn, Fn, ties):
    """Greedy selection in place: row ``i`` of ``X (P, D)`` and ``F (P,)`` becomes
    ``Xn[i], Fn[i]`` where ``Fn[i] < F[i]`` (``Fn[i] <= F[i]`` when ``ties`` is true).

    Returns:
        The number of replaced rows.
    """
    P, D = X.shape
    n = 0
    for i in range(P):
        if Fn[i] < F[i] or (ties and Fn[i] == F[i]):
            for d in range(D):
                X[i, d] = Xn[i, d]
            F[i] = Fn[i]
            n += 1
    return n


@numba.njit(cache=True)
def distinct_indices(U, pool, exclude_self):
    """Row ``i``: ``k`` distinct uniform indices into ``range(pool)`` from ``k`` uniforms.

    Sequential sampling without replacement and without rejection: the ``m``-th index is
    ``floor(u_m (pool - e))`` among the ``pool - e`` indices not yet excluded (``e``
    excluded so far), mapped past the excluded ones in increasing order. With
    ``exclude_self`` row ``i`` also excludes ``i`` (then ``i`` must be ``< pool``). Every
    ordered ``k``-tuple of allowed distinct indices has the same probability.

    Args:
        U: ``(n, k)`` uniforms in ``[0, 1)``.
        pool: number of indices to draw from; needs ``pool >= k + exclude_self``.
        exclude_self: also exclude the row number.

    Returns:
        ``(n, k)`` int64 indices.
    """
    n, k = U.shape
    out = np.empty((n, k), dtype=np.int64)
    taken = np.empty(k + 1, dtype=np.int64)      # excluded indices, kept sorted
    for i in range(n):
        e = 0
        if exclude_self:
            taken[0] = i
            e = 1
        for m in range(k):
            r = int(U[i, m] * (pool - e))
            if r >= pool - e:                     # guard against u rounding to 1
                r = pool - e - 1
            for q in range(e):                    # skip the excluded indices <= r
                if taken[q] <= r:
                    r += 1
            out[i, m] = r
            q = e                                 # insert r, keeping ``taken`` sorted
            while q > 0 and taken[q - 1] > r:
                taken[q] = taken[q - 1]
                q -= 1
            taken[q] = r
            e += 1
    return out
