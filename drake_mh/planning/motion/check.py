"""Certified straight motions for the compiled planners (``rrt_connect``, ``lazy_prm_star``).

:func:`certified_motion` decides whether a straight joint-space motion is collision-free over
its whole length: its interpolated states in batched calls with early exit (the scene's
:func:`drake_mh.scene.kernels.states.check_states`, VAMP's design: Thomason, Kingston, Kavraki,
"Motions in Microseconds via Vectorized Sampling-Based Planning", ICRA 2024), at clearances
raised by a margin that certifies the motion between the states (the Lipschitz bound of
:mod:`drake_mh.scene.kernels.segments`), refined only where a state is within the margin. Its
callers pass the arrays borrowed (:mod:`drake_mh._support.borrow`) in one
:class:`~drake_mh.scene.kernels.context.CheckContext` with the workspaces (:func:`workspaces`: its
per-motion arrays come from :func:`motion_workspace`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh._support.compilation import stable_calls
from drake_mh.planning.motion.clock import now
from drake_mh.planning.motion.stats import BY_MARGIN, BY_PROBES, MOTIONS, REFINE_EVALS, REFINED, REJECTED, \
    STATES, T_CERTIFY, T_CHECK
from drake_mh.scene.kernels import (CERTIFIED, CLEAR, COLLISION, check_blocks, check_states, segment_floor,
                                    state_workspace)
from drake_mh.scene.kernels import certify_segments as _certify_segments
from drake_mh.scene.pair_table import LOWEST

CERTIFIED_ROW = -1.0
"""``Λ_c`` of a row certified on the whole motion (a link pair by its floor table, any row that
kept its margins at every state of the first pass, see :func:`certified_motion`): no state
checks it."""


PROBES = (1.0, 0.5, 0.25, 0.125, 0.0625, 0.75, 0.375, 0.875)
"""Where on a motion (its parameter t) :func:`certified_motion` probes first, in this order, at
the plain clearances (``probes`` of :func:`motion_workspace` take the first ones). Of 9,554
MotionBenchMaker motions that the planner rejected (6 sets, cage left out, each checked on a
129-state grid), the end state collides in 52 %, and a state among t = 1, 1/2, 1/4, 1/8 in
97 %: their collisions start near the tree node (median t = 0.06-0.23) and cover most of the
motion. In the plans, 4 probes stop 97 % of a median plan's rejected motions (99.7 % of all)."""

INTERIOR_PROBES = (0.5, 0.25, 0.75, 0.125, 0.875, 0.375, 0.625, 0.0625)
"""The probes of a motion whose two ends are known free (:func:`certified_motion`'s
``interior``: the direct motion to a goal, a motion that ends on a tree node, a shortcut between
two points of the certified path): inside it only, middle first. With :data:`PROBES`, their
first probe (t = 1) was always free, and in a median MotionBenchMaker plan 2.6 of its 14
shortcut motions passed the probes and were rejected later, each after a first pass over all of
its states."""


@numba.njit(cache=True)
def motion_workspace(nq, C, G, capacity, probes, interior, clearance, self_clearance, t_grid):
    """Arrays :func:`certified_motion` writes into, for ``C`` constraint rows (``G`` links) and
    motions of up to ``capacity`` states (:func:`motion_capacity`; longer ones allocate their
    own): ``(lam (C,), QT (nq, capacity), order (capacity,), out (capacity,), margin rows (G,),
    (C - G,), plain rows (G,), (C - G,), inv_lam (C,), tau (capacity,), probe states
    (nq, L), plain clearances of the probes link (G,), pair (C - G,), probe out (L,), probe
    tau (L,), the motion's joint speeds |Δq| (nq,), (probes, interior))``, ``L`` the larger of
    ``probes`` and ``interior`` (how many states of :data:`PROBES` and of
    :data:`INTERIOR_PROBES` a motion probes), the probes' clearances filled: every link, and
    every link pair but those whose floor table's lowest floor keeps ``self_clearance``
    (``t_grid``, :mod:`drake_mh.scene.pair_table`: such a pair keeps it in every configuration,
    so it rejects no motion; 8 of the hand Panda's 12 pairs). A probe certifies nothing, it
    may only reject.
    Allocated once per plan: the first eight allocations were about 0.15 µs of a motion's 1.2 µs
    of setup (a replay of 132,349 MotionBenchMaker motions)."""
    P = C - G
    lam = np.zeros(C)
    for i in range(P):
        if t_grid[i, LOWEST] >= self_clearance + 1e-12:  # (certified_motion's test: -inf without a table)
            lam[G + i] = CERTIFIED_ROW
    link_plain, pair_plain = _clearances(lam, 0.0, G, clearance, self_clearance, np.empty(G), np.empty(P))
    L = max(probes, interior)
    return (np.empty(C), np.empty((nq, capacity)), np.empty(capacity, np.int64), np.empty(capacity, np.bool_),
            np.empty(G), np.empty(P), np.empty(G), np.empty(P), np.empty(C), np.empty(capacity),
            np.empty((nq, L)), link_plain, pair_plain, np.empty(L, np.bool_), np.empty(L),
            np.zeros(nq), np.array([probes, interior], np.int64))


@numba.njit(cache=True)
def workspaces(arrays, nq, C, lanes, capacity, probes, interior, clearance, self_clearance):
    """``(state workspace, motion workspace)`` of a plan
    (:func:`~drake_mh.scene.kernels.states.state_workspace`, :func:`motion_workspace`) for a
    scene's unpacked ``arrays``, ``C`` constraint rows, at most ``lanes`` states per call,
    ``probes`` probe states per motion and ``interior`` per motion between two free ends (0:
    none, at most 8) and the plan's clearances."""
    G = arrays[6].shape[0]
    return (state_workspace(arrays[0].shape[0], G, arrays[11].shape[0], C - G, max(lanes, probes, interior)),
            motion_workspace(nq, C, G, capacity, probes, interior, clearance, self_clearance, arrays[21]))


@numba.njit(cache=True)
def motion_capacity(span, reach, resolution, margin, most=4096):
    """States of the longest motion whose joint moves are at most ``span`` (``(nq,)`` [rad or m])
    as :func:`certified_motion` counts them (ends included), at most ``most``: the capacity of
    :func:`motion_workspace` (a longer motion allocates its own arrays)."""
    d, lam = 0.0, 0.0
    for j in range(span.shape[0]):
        if not math.isfinite(span[j]):  # a joint without limits
            return most
        d += span[j] * span[j]
    for c in range(reach.shape[0]):
        acc = 0.0
        for j in range(span.shape[0]):
            acc += reach[c, j] * span[j]
        lam = max(lam, acc)
    n = max(1.0, math.ceil(math.sqrt(d) * resolution), math.ceil(lam / (2.0 * margin)))
    return int(min(float(most), n + 1.0))


@numba.njit(cache=True)
def _clearances(lam, scale, G, clearance, self_clearance, link, pair):
    """``(link (G,), pair (P,))`` written: the required clearance of each constraint row plus
    ``scale · Λ_c`` (and 1e-12: the kernels compare squares, so "touching" must fail); ``-inf``
    for a row whose ``Λ_c`` is :data:`CERTIFIED_ROW` (``check_states`` skips it)."""
    for c in range(lam.shape[0]):
        if lam[c] == CERTIFIED_ROW:
            if c < G:
                link[c] = -np.inf
            else:
                pair[c - G] = -np.inf
        elif c < G:
            link[c] = clearance + scale * lam[c] + 1e-12
        else:
            pair[c - G] = self_clearance + scale * lam[c] + 1e-12
    return link, pair


@numba.njit(cache=True)
def _refine(qa, qb, tau, order, n, lam, inv_lam, speeds, plain, clearance, self_clearance, ctx, lanes, max_evals):
    """Certify ``qa -> qb`` by conservative advancement from both ends of each piece, or find a
    collision on it (see :func:`certified_motion`).

    A state at ``t`` whose rows keep ``V_c >= clearance_c + Λ_c τ`` certifies ``[t - τ, t + τ]``
    (the Lipschitz bound), so a piece ``[t0, t1]`` is certified when ``τ0 + τ1 >= t1 - t0``.
    ``tau[w]`` is state ``order[w]``'s ``τ`` (:func:`~drake_mh.scene.kernels.states.check_states`:
    from the clearance values of the rows below their margins, for a link also from where the
    joint axes are in that state and the motion's joint ``speeds``; a state that kept every
    margin has ``τ >= 1 / 2n``). Each round checks, in one batched call, the middle of the gap
    ``[t0 + τ0, t1 - τ1]`` of every piece not yet certified, at margins for half that gap: a
    middle that keeps them certifies both halves, and one that does not shrinks each half's gap
    below half the old one. Every state is evaluated once (no end is checked again at smaller
    margins). Stops when every piece is certified, on a collision, or after ``max_evals``
    configurations (undecided: not certified).

    Returns:
        ``(certified, configurations evaluated)``.
    """
    nq = qa.shape[0]
    G = ctx.arrays[6].shape[0]
    total = n + 1
    lam_max = 0.0
    for c in range(lam.shape[0]):
        lam_max = max(lam_max, lam[c])
    half = 0.5 / n
    ts = np.empty(total)
    tv = np.empty(total)
    for w in range(total):
        ts[order[w]] = order[w] / n
        tv[order[w]] = min(tau[w], half)
    # pieces not certified: (t0, τ0, t1, τ1), rows of P (each round writes the next pieces into N);
    # the arrays are allocated once per motion, not per round
    cap = 2 * n
    P, N = np.empty((cap, 4)), np.empty((cap, 4))
    count = 0
    for i in range(n):  # (both ends kept the margins: certified, as in step 1)
        if (tv[i] < half or tv[i + 1] < half) and tv[i] + tv[i + 1] < ts[i + 1] - ts[i]:
            P[count, 0], P[count, 1], P[count, 2], P[count, 3] = ts[i], tv[i], ts[i + 1], tv[i + 1]
            count += 1
    tm, half_gap, QE = np.empty(cap), np.empty(cap), np.empty((nq, cap))
    kept, tau_m = np.empty(cap, np.bool_), np.empty(cap)
    margin_rows = (np.empty(G), np.empty(lam.shape[0] - G))
    evals = 0
    while count > 0:
        if 2 * count > cap:  # (rare: the pieces doubled beyond the first round's room)
            cap = 2 * count
            P2, N = np.empty((cap, 4)), np.empty((cap, 4))
            P2[:count] = P[:count]
            P = P2
            tm, half_gap, QE = np.empty(cap), np.empty(cap), np.empty((nq, cap))
            kept, tau_m = np.empty(cap, np.bool_), np.empty(cap)
        # each piece's middle state tm and the τ it needs (half its gap); margins for the largest
        need = 0.0
        for r in range(count):
            a, b = P[r, 0] + P[r, 1], P[r, 2] - P[r, 3]
            tm[r], half_gap[r] = 0.5 * (a + b), 0.5 * (b - a)
            need = max(need, half_gap[r])
        if evals + count > max_evals or lam_max * need < 1e-9:
            return False, evals
        margins = _clearances(lam, need, G, clearance, self_clearance, margin_rows[0], margin_rows[1])
        for r in range(count):
            for j in range(nq):
                QE[j, r] = qa[j] + tm[r] * (qb[j] - qa[j])
        answer, used = check_blocks(QE, count, (lanes[1], lanes[1]), margins, plain, inv_lam, speeds, ctx, kept, tau_m)
        evals += used
        if answer == COLLISION:
            return False, evals
        c2 = 0
        for r in range(count):
            vm = tau_m[r]
            if vm >= half_gap[r]:  # it certifies half the gap on each side
                continue
            N[c2, 0], N[c2, 1], N[c2, 2], N[c2, 3] = P[r, 0], P[r, 1], tm[r], vm
            N[c2 + 1, 0], N[c2 + 1, 1], N[c2 + 1, 2], N[c2 + 1, 3] = tm[r], vm, P[r, 2], P[r, 3]
            c2 += 2
        P, N, count = N, P, c2
    return True, evals


@numba.njit(cache=True, inline="always")
def probe_collides(qa, qb, ctx, interior):
    """Whether one of the motion's probe states (:data:`PROBES`, or :data:`INTERIOR_PROBES` for
    a motion whose ends are known free; as many as the workspace says) collides at the plain
    clearances: one batched call before any of the motion's setup."""
    mws = ctx.mws
    PT = mws[10]
    probes = mws[16][1] if interior else mws[16][0]
    if probes == 0:
        return False
    for w in range(probes):
        t = INTERIOR_PROBES[w] if interior else PROBES[w]
        for j in range(qa.shape[0]):
            PT[j, w] = qa[j] + t * (qb[j] - qa[j])
    # margins = plain clearances: the answer is COLLISION or CLEAR, no tau (so the speeds, still the
    # previous motion's, are not read)
    link, pair = mws[11], mws[12]
    return check_states(PT, 0, probes, link, pair, link, pair, mws[8], mws[15], ctx, mws[13], mws[14]) == COLLISION


@stable_calls()
@numba.njit(cache=True)
def certified_motion(qa, qb, ctx, lanes, v_WO, reach, clearance, self_clearance, resolution, max_margin, max_evals,
                     by_values, stats, clock, buf, profile, interior):
    """Whether the straight motion ``qa -> qb`` is **certified** collision-free (``qa`` free;
    ``interior``: ``qb`` known free too, e.g. a tree node or a point of a certified path, so
    the probes are inside the motion; a hint that changes the cost, never the answer).

    Every constraint row ``c`` (a link against the obstacles, a checked link pair) changes
    along the motion no faster than ``Λ_c = Σ_j reach[c, j] |Δq_j|`` per unit of t (the
    Lipschitz bound of :mod:`drake_mh.scene.kernels.segments`, from
    :attr:`~drake_mh.scene.batch.CollisionModel.reach`). A link pair with a floor table
    (:mod:`drake_mh.scene.pair_table`) whose cells along the motion all keep the pair's clearance
    is certified on the whole motion by them (:func:`drake_mh.scene.kernels.pairs.segment_floor`):
    its ``Λ_c`` is :data:`CERTIFIED_ROW` and no state checks that pair (its clearance rows are
    ``-inf``: neither its bounding spheres, nor its table, nor its sphere pairs).

    0. The probes (:func:`probe_collides`: states of :data:`PROBES`, or with ``interior`` of
       :data:`INTERIOR_PROBES`, as many as the workspace says, 0 to skip): one batched call at
       the plain clearances, before any of the motion's setup; a probe that collides rejects
       the motion (the statistics' ``BY_PROBES``). A probe certifies nothing, so the answer is
       the same with or without them.
    1. ``n`` pieces, ``n >= resolution · |qb - qa|`` and ``n >= max_c Λ_c / (2 max_margin)``;
       the ``n + 1`` states ``t = i / n`` (ends included), in VAMP's "rake" order (``lanes[0]``
       states spread over the whole motion first, so that a collision is found early, then
       blocks of ``lanes[1]``), are checked block by block
       (:func:`drake_mh.scene.kernels.states.check_states`), each row at its clearance raised
       by the margin ``Λ_c / (2 n)`` and, where a sphere is below that, at the plain
       clearance. A state below the plain clearance rejects the motion at once (early exit).
       If every state keeps the margins, every piece is certified, since
       ``V_c(t) >= (V0 + V1 - Λ_c / n) / 2 >= clearance`` on it: most motions that are not
       rejected end here, certified by the boolean check alone.
    2. Otherwise (free, but within the margins somewhere) a refinement decides, with at most
       ``max_evals`` configurations (undecided: rejected), on the rows that came within their
       margins only: a row that kept them at every state is certified on every piece, so no
       later state checks it. With ``by_values`` None, :func:`_refine`: conservative
       advancement from both ends of each uncertain piece on the clearance values the check
       reports for those rows, with the links' local bound on ``τ``
       (:func:`drake_mh.scene.kernels.states._link_tau`; 26 configurations per refined
       MotionBenchMaker motion, against 70 for the bisection), else (any
       other value, e.g. True) the scene's
       :func:`drake_mh.scene.kernels.segments.certify_segments` (the bound on clearance values
       from :func:`~drake_mh.scene.kernels.collision.link_clearances`). The choice is made at
       compile time from the argument's type, so the default (None) does not compile the
       second: 35 s less from an empty numba cache.

    The compiled core ports this function with ``by_values`` None (``cpp/motion.hpp``, the same
    steps, answers and statistics; ``rrt_connect`` calls it where the core is built); the
    bisection (``by_values`` True, ``certify="bisection"``) runs here, in numba, only.
    """
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = ctx.arrays
    ws, mws = ctx.ws, ctx.mws
    t0 = now(clock, buf) if profile else 0.0
    nq = qa.shape[0]
    G, C = g_anchor.shape[0], reach.shape[0]
    stats[STATES] += mws[16][1] if interior else mws[16][0]
    if probe_collides(qa, qb, ctx, interior):
        stats[MOTIONS] += 1
        stats[REJECTED] += 1
        stats[BY_PROBES] += 1
        if profile:
            stats[T_CHECK] += now(clock, buf) - t0
        return False
    d = 0.0
    speeds = mws[15]
    for j in range(nq):
        d += (qb[j] - qa[j]) ** 2
        speeds[j] = abs(qb[j] - qa[j])
    d = math.sqrt(d)
    lam = mws[0]
    lam_max = 0.0
    for c in range(C):
        acc = 0.0
        for j in range(nq):
            acc += reach[c, j] * abs(qb[j] - qa[j])
        # the pair's table certifies it along the whole motion: no state checks it. Pairs without a
        # table (a call passing five arrays costs about 35 ns), and tables whose lowest floor keeps
        # the clearance everywhere (8 of the hand Panda's 12), are settled here without a walk:
        # the MotionBenchMaker median plan 1.54 -> 1.40 (the first) -> 1.30 ms (both), same trees
        if c >= G and t_meta[c - G, 0] != 0 and (t_grid[c - G, LOWEST] >= self_clearance + 1e-12 or segment_floor(
                c - G, qa, qb, t_meta, t_grid, t_vals) >= self_clearance + 1e-12):
            acc = CERTIFIED_ROW
        lam[c] = acc
        lam_max = max(lam_max, acc)
    n = max(1, int(math.ceil(d * resolution)), int(math.ceil(lam_max / (2.0 * max_margin))))
    total = n + 1
    rakes = (total + lanes[0] - 1) // lanes[0]
    if total <= mws[1].shape[1]:
        QT, order, out = mws[1], mws[2], mws[3]
    else:
        QT, order, out = np.empty((nq, total)), np.empty(total, np.int64), np.empty(total, np.bool_)
    w = 0
    for r in range(rakes):  # column w: state i = r + k · rakes
        i = r
        while i < total:
            t = i / n
            for j in range(nq):
                QT[j, w] = qa[j] + t * (qb[j] - qa[j])
            order[w] = i
            w += 1
            i += rakes
    margins = _clearances(lam, 1.0 / (2 * n), G, clearance, self_clearance, mws[4], mws[5])
    plain = _clearances(lam, 0.0, G, clearance, self_clearance, mws[6], mws[7])
    inv_lam, tau = mws[8], mws[9] if total <= mws[9].shape[0] else np.empty(total)
    for c in range(C):
        inv_lam[c] = 1.0 / lam[c] if lam[c] > 0.0 else 0.0
    rows_near = ws[22]
    rows_near[:] = False
    answer, used = check_blocks(QT, total, lanes, margins, plain, inv_lam, speeds, ctx, out, tau)
    stats[MOTIONS] += 1
    stats[STATES] += used
    if profile:
        t1 = now(clock, buf)
        stats[T_CHECK] += t1 - t0
        t0 = t1
    if answer == COLLISION:
        stats[REJECTED] += 1
        return False
    if answer == CLEAR:
        stats[BY_MARGIN] += 1
        return True
    if by_values is None:  # a compile-time branch (numba prunes it by the argument's type)
        # a row that kept its margins at every state is certified on the whole motion
        for c in range(C):
            if not rows_near[c]:
                lam[c] = CERTIFIED_ROW
        plain = _clearances(lam, 0.0, G, clearance, self_clearance, mws[6], mws[7])
        certified, evals = _refine(qa, qb, tau, order, n, lam, inv_lam, speeds, plain, clearance, self_clearance,
                                   ctx, lanes, max_evals)
    else:
        QA = np.empty((1, nq))
        QB = np.empty((1, nq))
        QA[0], QB[0] = qa, qb
        status, t_stop = np.empty(1, np.int64), np.empty(1)
        lower, lower_self, spent = np.empty(1), np.empty(1), np.empty(1, np.int64)
        _certify_segments(QA, QB, reach, 0.0, clearance, self_clearance, np.inf, 1e-9, max_evals,
                          parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
                          kinds, R_WO, p_WO, v_WO, dims, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart,
                          u_start, u_offset, u_radius, status, t_stop, lower, lower_self, spent)
        certified, evals = status[0] == CERTIFIED, spent[0]
    stats[REFINED] += 1
    stats[REFINE_EVALS] += evals
    if profile:
        stats[T_CERTIFY] += now(clock, buf) - t0
    if not certified:
        stats[REJECTED] += 1
        return False
    return True
