"""Numba kernel behind :mod:`drake_mh.scene.segments`: certify straight joint-space segments.

Per segment ``q(t) = q_a + t (q_b - q_a)``, ``t in [0, 1]``, every constraint value ``V_c``
of :func:`drake_mh.scene.kernels.collision.link_clearances` (per link: clearance to the
obstacles; per checked link pair: self clearance) is Lipschitz in ``t`` with constant
``Λ_c = Σ_j reach[c, j] |Δq_j|`` (plus the obstacles' largest displacement for link rows),
because each value is a distance that changes no faster than the geometry moves
(:attr:`drake_mh.scene.batch.CollisionModel.reach`). Over a piece ``[t0, t1]`` of length
``h`` with end values ``V0``, ``V1``::

    V_c(t) >= max(V0 - Λ_c (t - t0), V1 - Λ_c (t1 - t)) >= (V0 + V1 - Λ_c h) / 2

so a piece whose bound is at least the required clearance is certified, *for every t in it*.

Pieces that are not are cut in two (all of one level evaluated together, in SIMD blocks)
until every piece is certified, a configuration below the clearance is found, or a piece is
shorter than ``min_piece`` (undecided: a touching contact cannot be certified either way).

A link's value has a second bound from its curvature where no obstacle is a convex mesh piece
(whose value, the largest of its planes' distances, has kinks). Each of its sphere-obstacle
values ``d(x(t)) - r`` is at least the Lipschitz bound ``L`` on the piece, so the centre keeps
``d >= L + r_min`` from the obstacle (``r_min``: the link's smallest sphere), where the
distance to a convex set (or a cloud point) curves by at most ``1 / d``; with
``|x'| <= Λ_c`` and ``|x''| <= A_c = Σ_jk |Δq_j| |Δq_k| max(reach[c, j], reach[c, k])`` (a
second derivative of a point of a chain along two joints is at most its distance from the
later joint's axis; 1 for a prismatic joint)::

    d(x(t))'' <= Λ_c² / (L + r_min) + A_c = K

and the minimum of such values keeps ``V_c(t) >= chord(t) - K (t - t0) (t1 - t) / 2``; the
piece's bound is the larger of ``L`` and that parabola's smallest value. Near a minimum it
shrinks as ``h²`` instead of ``h``: a tight bound needs far fewer configurations
(``studies/segment_certificates.py``).

A link pair with a floor table (:mod:`drake_mh.scene.pair_table`) whose cells along the segment
all keep the self-clearance is certified by them on the whole segment
(:func:`drake_mh.scene.kernels.pairs.segment_floor`, also its ``lower_self``): its value is
then not computed beyond the bounding spheres.
"""

from __future__ import annotations

import numba
import numpy as np

from drake_mh._support.borrow import borrow
from drake_mh.scene.kernels.collision import FASTMATH, PER_LINK, link_clearances
from drake_mh.scene.kernels.pairs import segment_floor
from drake_mh.scene.kernels.pieces import CONVEX

CERTIFIED, BLOCKED, UNDECIDED = 1, 0, -1


@numba.njit(cache=True, fastmath=FASTMATH)
def _bound(V0, V1, lam, h):
    return min(min(V0, V1), 0.5 * (V0 + V1 - lam * h))


@numba.njit(cache=True, fastmath=FASTMATH)
def _curved_bound(V0, V1, lam, acc, rmin, h):
    """A link row's bound on a piece from the curvature of its value (module docstring): the
    larger of the Lipschitz bound ``L`` and the smallest value of the chord less
    ``K (t - t0) (t1 - t) / 2``, ``K = lam² / (L + rmin) + acc``."""
    L = _bound(V0, V1, lam, h)
    delta = L + rmin
    if not delta > 0.0 or not abs(V0) < np.inf or not abs(V1) < np.inf:
        return L
    a = 0.5 * (lam * lam / delta + acc) * h * h
    D = V1 - V0
    if not a > 0.0:
        return max(L, min(V0, V1))
    u = min(max((a - D) / (2.0 * a), 0.0), 1.0)
    return max(L, V0 + D * u - a * u * (1.0 - u))


@numba.njit(cache=True, fastmath=FASTMATH)
def certify_segments(QA, QB, reach, speed, clearance, self_clearance, tolerance, min_piece, max_evals,
                     parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
                     kinds, R_WO, p_WO, v_WO, dims, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart,
                     u_start, u_offset, u_radius, status, t_stop, lower, lower_self, evals):
    """Certify each segment ``QA[i] -> QB[i]`` (module docstring).

    Args:
        reach: ``(C, nq)`` per-constraint reach (links, then pairs).
        speed: largest obstacle displacement over a whole segment [m] (``v_WO`` per unit t).
        clearance, self_clearance: required values of link and pair rows [m].
        tolerance: also cut certified pieces whose bound is more than this below the smallest
            value seen at their ends (``inf``: certification only).
        min_piece: shortest piece in t before giving up (UNDECIDED).
        max_evals: most configurations evaluated per segment (then UNDECIDED).

    Outputs (per segment): ``status`` (CERTIFIED, BLOCKED, UNDECIDED), ``t_stop`` (t of the first
    configuration found below the clearance, or of the undecided piece; NaN if certified),
    ``lower`` / ``lower_self`` (certified lower bound of the link / pair rows over the whole
    segment, where certified), ``evals`` (configurations evaluated).
    """
    # the arrays are the caller's for the whole call: passed on without reference counts (drake_mh._support.borrow)
    (reach, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius, kinds, R_WO,
     p_WO, v_WO, dims, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius) = borrow(
        (reach, parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius, kinds, R_WO,
         p_WO, v_WO, dims, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius))
    G = g_anchor.shape[0]
    C = reach.shape[0]
    nq = QA.shape[1]
    # fine spheres below 5 cm above the requirement (bounding spheres above it); for the links,
    # everywhere when a tight bound is asked for (the tolerance concerns the obstacle clearance:
    # link pairs need only be certified, and exact pairs everywhere cost 40x on meshed arms)
    fine = min(clearance, self_clearance) + 0.05 if tolerance == np.inf else np.inf
    pair_fine = min(clearance, self_clearance) + 0.05 if tolerance == np.inf else self_clearance + 0.05
    lam = np.empty(C)
    P = C - G
    # the curvature bound of the link rows: every obstacle's distance smooth and convex outside it
    # (not a convex mesh piece's, the largest of its planes' distances); per link its smallest sphere
    curved = True
    for k in range(kinds.shape[0]):
        curved &= kinds[k] != CONVEX
    rmin = np.full(G, np.inf)
    for g in range(G):
        for k in range(g_start[g], g_start[g + 1]):
            rmin[g] = min(rmin[g], s_radius[k])
    acc = np.zeros(G)
    fines, tabled, floors = np.empty(P), np.empty(P, np.bool_), np.empty(P)
    for i in range(QA.shape[0]):
        # pairs whose floor table keeps them clear along the whole segment: certified by it, and
        # computed no further than their bounding spheres (drake_mh.scene.pair_table)
        for q in range(P):
            # a pair without a table told apart here, not in a call (one that passes five arrays
            # costs about 35 ns; inlining segment_floor's test measured slower)
            floors[q] = segment_floor(q, QA[i], QB[i], t_meta, t_grid, t_vals) if t_meta[q, 0] != 0 else -np.inf
            tabled[q] = floors[q] >= self_clearance
            fines[q] = -np.inf if tabled[q] else pair_fine
        cap = 64
        vals = np.empty((cap, C))
        ts = np.empty(cap)
        for c in range(C):
            total = 0.0
            for j in range(nq):
                total += reach[c, j] * abs(QB[i, j] - QA[i, j])
            lam[c] = total + (speed if c < G else 0.0)
        for c in range(G if curved else 0):  # |x''| <= sum_jk |dq_j| |dq_k| max(reach_j, reach_k)
            total = 0.0
            for j in range(nq):
                for k in range(nq):
                    total += abs(QB[i, j] - QA[i, j]) * abs(QB[i, k] - QA[i, k]) * max(reach[c, j], reach[c, k])
            acc[c] = total
        QT = np.empty((nq, 2))
        for j in range(nq):
            QT[j, 0], QT[j, 1] = QA[i, j], QB[i, j]
        ts[0], ts[1] = 0.0, 1.0
        link_clearances(QT, ts[:2].copy(), fine, fines, PER_LINK, parent, KR, Kp, perm, kind, qidx, g_anchor,
                        g_offset, g_radius, g_start, s_offset, s_radius, kinds, R_WO, p_WO, v_WO, dims, pair_a, pair_b,
                        t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius, vals[:2])
        n = 2
        status[i], t_stop[i] = CERTIFIED, np.nan
        low, low_self = np.inf, np.inf
        for e in range(2):
            for c in range(C):
                if vals[e, c] < (clearance if c < G else self_clearance) and not (c >= G and tabled[c - G]):
                    if status[i] == CERTIFIED:
                        status[i], t_stop[i] = BLOCKED, ts[e]
        if status[i] == BLOCKED:
            lower[i], lower_self[i], evals[i] = np.nan, np.nan, n
            continue
        pieces = np.empty((1, 2), np.int64)
        pieces[0, 0], pieces[0, 1] = 0, 1
        while pieces.shape[0] > 0 and status[i] == CERTIFIED:
            split = np.empty(pieces.shape[0], np.bool_)
            count = 0
            for r in range(pieces.shape[0]):
                e0, e1 = pieces[r, 0], pieces[r, 1]
                h = ts[e1] - ts[e0]
                ok, lo, lo_self, seen = True, np.inf, np.inf, np.inf
                for c in range(C):
                    if c >= G and tabled[c - G]:
                        bound = floors[c - G]  # the whole segment's floor
                    elif c < G and curved:
                        bound = _curved_bound(vals[e0, c], vals[e1, c], lam[c], acc[c], rmin[c], h)
                    else:
                        bound = _bound(vals[e0, c], vals[e1, c], lam[c], h)
                    if c < G:
                        ok &= bound >= clearance
                        lo = min(lo, bound)
                        seen = min(seen, min(vals[e0, c], vals[e1, c]))
                    else:
                        ok &= bound >= self_clearance
                        lo_self = min(lo_self, bound)
                if ok and not lo < seen - tolerance:
                    split[r] = False
                    low, low_self = min(low, lo), min(low_self, lo_self)
                    continue
                if h < min_piece or n + count + 1 > max_evals:
                    if ok:  # certified, only not as tight as asked
                        split[r] = False
                        low, low_self = min(low, lo), min(low_self, lo_self)
                        continue
                    status[i], t_stop[i] = UNDECIDED, ts[e0]
                    break
                split[r] = True
                count += 1
            if status[i] != CERTIFIED or count == 0:
                break
            while n + count > cap:  # grow the store
                cap *= 2
                grown_v, grown_t = np.empty((cap, C)), np.empty(cap)
                grown_v[:n], grown_t[:n] = vals[:n], ts[:n]
                vals, ts = grown_v, grown_t
            QT = np.empty((nq, count))
            tau = np.empty(count)
            new = np.empty((2 * count, 2), np.int64)
            w = 0
            for r in range(pieces.shape[0]):
                if not split[r]:
                    continue
                e0, e1 = pieces[r, 0], pieces[r, 1]
                t = 0.5 * (ts[e0] + ts[e1])
                ts[n + w], tau[w] = t, t
                for j in range(nq):
                    QT[j, w] = QA[i, j] + t * (QB[i, j] - QA[i, j])
                new[2 * w, 0], new[2 * w, 1] = e0, n + w
                new[2 * w + 1, 0], new[2 * w + 1, 1] = n + w, e1
                w += 1
            link_clearances(QT, tau, fine, fines, PER_LINK, parent, KR, Kp, perm, kind, qidx, g_anchor,
                            g_offset, g_radius, g_start, s_offset, s_radius, kinds, R_WO, p_WO, v_WO, dims, pair_a,
                            pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start, u_offset, u_radius,
                            vals[n:n + count])
            first = np.inf
            for w in range(count):
                for c in range(C):
                    if vals[n + w, c] < (clearance if c < G else self_clearance) and not (c >= G and tabled[c - G]):
                        first = min(first, ts[n + w])
            n += count
            if first < np.inf:
                status[i], t_stop[i] = BLOCKED, first
                break
            pieces = new
        evals[i] = n
        if status[i] == CERTIFIED:
            lower[i], lower_self[i] = low, low_self
        else:
            lower[i], lower_self[i] = np.nan, np.nan
