"""Random shortcutting of a certified path, compiled: what ``rrt_connect`` and ``lazy_prm_star``
do to every path they find.

* :func:`drop_collinear` — waypoints on the segment between their neighbours removed;
* :func:`shortcut` — random shortcuts, each certified by :func:`~.check.certified_motion`;
* :func:`arc_lengths` — a path's length to each waypoint.

Randomness: :mod:`drake_mh._support.random` (SplitMix64) on the caller's state array.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh._support.random import uniform
from drake_mh.planning.motion.check import certified_motion
from drake_mh.planning.motion.clock import now
from drake_mh.planning.motion.stats import SHORTCUTS_KEPT, SHORTCUTS_TRIED, T_SHORTCUT

__all__ = ["drop_collinear", "shortcut", "arc_lengths"]


@numba.njit(cache=True)
def drop_collinear(path):
    """Remove waypoints that lie on the segment between their neighbours (the straight runs of
    CONNECT: the union of certified collinear segments is the one segment)."""
    M, nq = path.shape
    keep = np.ones(M, np.bool_)
    last = 0
    for k in range(1, M - 1):
        a, b, c = path[last], path[k], path[k + 1]
        ab, ac, dot = 0.0, 0.0, 0.0
        for j in range(nq):
            ab += (b[j] - a[j]) ** 2
            ac += (c[j] - a[j]) ** 2
            dot += (b[j] - a[j]) * (c[j] - a[j])
        # b on [a, c]: |ab| |ac| == ab·ac (parallel, same direction) and |ab| <= |ac|
        if ab <= ac and ac > 0.0 and dot * dot >= ab * ac * (1.0 - 1e-14) and dot > 0.0:
            keep[k] = False
        else:
            last = k
    return path[keep].copy()


@numba.njit(cache=True)
def arc_lengths(path):
    """``(M,)`` the path's length [rad] from its first waypoint to each waypoint."""
    M, nq = path.shape
    s = np.zeros(M)
    for k in range(M - 1):
        d = 0.0
        for j in range(nq):
            d += (path[k + 1, j] - path[k, j]) ** 2
        s[k + 1] = s[k] + math.sqrt(d)
    return s


@numba.njit(cache=True)
def shortcut(path, iterations, min_gain, rng, ctx, lanes, v_WO, reach, clearance, self_clearance,
             resolution, margin, max_evals, by_values, stats, clock, buf, profile, start, time_limit):
    """Random shortcutting (Geraerts & Overmars, "Creating high-quality paths for motion
    planning", IJRR 2007): join two random points of the path by a certified straight motion
    (:func:`drake_mh.planning.motion.check.certified_motion`) when that is shorter, ``iterations`` draws or until the
    deadline. The pieces kept of the old segments are parts of certified segments.

    A draw that would shorten the path by less than ``min_gain`` of its length
    (``(v - u) - |qb - qa| < min_gain · L``) is not checked: such shortcuts mostly hug the path,
    so most of them are certified (the expensive answer, many states near obstacles) for little
    length (see :class:`~drake_mh.planning.rrt_connect.RRTConnectConfig`'s ``shortcut_min_gain``)."""
    t0 = now(clock, buf) if profile else 0.0
    nq = path.shape[1]
    qa, qb = np.empty(nq), np.empty(nq)  # copied into the new path
    s = arc_lengths(path)
    for _ in range(iterations):
        M = path.shape[0]
        if M <= 2 or now(clock, buf) - start > time_limit:
            break
        L = s[M - 1]
        u, v = uniform(rng) * L, uniform(rng) * L
        if u > v:
            u, v = v, u
        i = 0
        while i < M - 2 and s[i + 1] <= u:
            i += 1
        k = i
        while k < M - 2 and s[k + 1] <= v:
            k += 1
        if k == i:
            continue
        ha, hb = s[i + 1] - s[i], s[k + 1] - s[k]
        ta = (u - s[i]) / ha if ha > 0 else 0.0
        tb = (v - s[k]) / hb if hb > 0 else 0.0
        chord = 0.0
        for j in range(nq):
            qa[j] = path[i, j] + ta * (path[i + 1, j] - path[i, j])
            qb[j] = path[k, j] + tb * (path[k + 1, j] - path[k, j])
            chord += (qb[j] - qa[j]) ** 2
        if (v - u) - math.sqrt(chord) < min_gain * L:
            continue
        stats[SHORTCUTS_TRIED] += 1
        if not certified_motion(qa, qb, ctx, lanes, v_WO, reach, clearance, self_clearance, resolution,
                                margin, max_evals, by_values, stats, clock, buf, profile, True):
            continue
        stats[SHORTCUTS_KEPT] += 1
        # path[:i+1], qa (unless it is path[i]), qb (unless it is path[k+1]), path[k+1:]
        add_a, add_b = ta > 0.0, tb < 1.0
        new = np.empty((i + 1 + add_a + add_b + M - k - 1, nq))
        new[:i + 1] = path[:i + 1]
        r = i + 1
        if add_a:
            new[r] = qa
            r += 1
        if add_b:
            new[r] = qb
            r += 1
        new[r:] = path[k + 1:]
        path = new
        s = arc_lengths(path)
    if profile:
        stats[T_SHORTCUT] += now(clock, buf) - t0
    return path
