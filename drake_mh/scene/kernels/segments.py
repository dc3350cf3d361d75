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

CERTIFIED, BLOCKED, UNDECIDED = 1, 0, -1


@numba.njit(cache=True, fastmath=FASTMATH)
def _bound(V0, V1, lam, h):
    return min(min(V0, V1), 0.5 * (V0 + V1 - lam * h))


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
            acc = 0.0
            for j in range(nq):
                acc += reach[c, j] * abs(QB[i, j] - QA[i, j])
            lam[c] = acc + (speed if c < G else 0.0)
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
