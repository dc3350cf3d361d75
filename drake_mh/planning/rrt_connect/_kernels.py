"""Compiled RRT-Connect: sampling, nearest neighbours, certified motions, shortcutting.

Everything from the first sample to the shortcut path runs in one numba call
(:func:`plan_kernel`); the only Python is the call itself. Every motion (tree edge, direct
connection, shortcut) goes through :func:`_motion`: its interpolated states in batched calls
with early exit (the scene's :func:`drake_mh.scene._state_kernels.check_states`, VAMP's
design: Thomason, Kingston, Kavraki, "Motions in Microseconds via Vectorized Sampling-Based
Planning", ICRA 2024), at clearances raised by a
margin that certifies the motion between the states (the Lipschitz bound of
:mod:`drake_mh.scene._segment_kernel`), refined by bisection only where a state is within the
margin.

Randomness: splitmix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators",
OOPSLA 2014) on a state array seeded from the caller's ``numpy.random.Generator``: the same
seed gives the same path, whatever else runs in the process.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh.planning.rrt_connect._clock import now
from drake_mh.scene._packing import _unpack
from drake_mh.scene._pair_kernel import segment_floor
from drake_mh.scene._segment_kernel import CERTIFIED
from drake_mh.scene._segment_kernel import certify_segments as _certify_segments
from drake_mh.scene._state_kernels import CLEAR, COLLISION, check_blocks, state_workspace
from drake_mh.scene.pair_table import LOWEST

FOUND, BUDGET, TIMEOUT = 0, 1, 2
"""Outcomes of :func:`plan_kernel`."""

# --- statistics (one float64 array, filled by the kernel) --------------------------------------
ITERATIONS, NODES, NN_SCANS, MOTIONS, STATES, BY_MARGIN, REFINED, REFINE_EVALS, REJECTED, \
    SHORTCUTS_TRIED, SHORTCUTS_KEPT, T_SAMPLE, T_NN, T_CHECK, T_CERTIFY, T_SHORTCUT, T_TOTAL = range(17)
STAT_NAMES = ("iterations", "nodes", "nn_scans", "motions", "states", "certified_by_margin", "refined",
              "refine_evals", "rejected", "shortcuts_tried", "shortcuts_kept", "t_sample", "t_nn",
              "t_check", "t_certify", "t_shortcut", "t_total")

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)


@numba.njit(cache=True, inline="always")
def _next(state):
    """splitmix64: the next 64 random bits (``state`` a ``(1,)`` uint64 array)."""
    z = state[0] + _GOLDEN
    state[0] = z
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@numba.njit(cache=True, inline="always")
def _uniform(state):
    """Uniform in [0, 1) with 53 random bits."""
    return np.float64(_next(state) >> _S11) * (1.0 / 9007199254740992.0)


@numba.njit(cache=True, inline="always")
def _below(state, n):
    """Uniform integer in [0, n)."""
    return min(int(_uniform(state) * n), n - 1)


@numba.njit(cache=True)
def _nearest(V, n, q):
    """Index of the row of ``V[:n]`` nearest to ``q`` (Euclidean, linear scan)."""
    best, arg = np.inf, 0
    nq = q.shape[0]
    for i in range(n):
        d = 0.0
        for j in range(nq):
            e = V[i, j] - q[j]
            d += e * e
        if d < best:
            best, arg = d, i
    return arg


@numba.njit(cache=True)
def _steer(qa, qb, step, out):
    """``out`` = ``qb`` if within ``step`` of ``qa``, else the point ``step`` from ``qa`` toward it;
    returns whether ``qb`` was reached."""
    d = 0.0
    for j in range(qa.shape[0]):
        d += (qb[j] - qa[j]) ** 2
    d = math.sqrt(d)
    if d <= step:
        out[:] = qb
        return True
    s = step / d
    for j in range(qa.shape[0]):
        out[j] = qa[j] + s * (qb[j] - qa[j])
    return False


CERTIFIED_ROW = -1.0
"""``Λ_c`` of a link pair certified on the whole motion by its floor table: no state checks it."""


@numba.njit(cache=True)
def _clearances(lam, scale, G, clearance, self_clearance):
    """``(link (G,), pair (P,))``: the required clearance of each constraint row plus
    ``scale · Λ_c`` (and 1e-12: the kernels compare squares, so "touching" must fail); ``-inf``
    for a pair row whose ``Λ_c`` is :data:`CERTIFIED_ROW` (``check_states`` skips it)."""
    link, pair = np.empty(G), np.empty(lam.shape[0] - G)
    for c in range(lam.shape[0]):
        if c < G:
            link[c] = clearance + scale * lam[c] + 1e-12
        elif lam[c] == CERTIFIED_ROW:
            pair[c - G] = -np.inf
        else:
            pair[c - G] = self_clearance + scale * lam[c] + 1e-12
    return link, pair


@numba.njit(cache=True)
def _refine(qa, qb, out, order, n, lam, plain, clearance, self_clearance, arrays, ws, lanes, max_evals):
    """Certify ``qa -> qb`` by boolean bisection, or find a collision on it (see :func:`_motion`).

    A piece of length ``h`` (in t) is certified when both its ends pass the batched check with
    every constraint row ``c`` (link, link pair) at its clearance raised by ``Λ_c h / 2``.
    Level ``L`` halves the pieces of level ``L - 1`` that are not certified: their midpoints
    are checked at the level's margins and the plain clearances (a collision ends it), their
    ends again at the smaller margins, every level in one batched call. Stops when every piece
    is certified, on a collision, or after ``max_evals`` configurations (undecided: not
    certified).

    ``out[w]``: whether state ``order[w]`` (``t = order[w] / n``) kept the level-0 margins;
    every state is free at the plain clearances.

    Returns:
        ``(certified, configurations evaluated)``.
    """
    nq = qa.shape[0]
    G = arrays[6].shape[0]
    total = n + 1
    lam_max = 0.0
    for c in range(lam.shape[0]):
        lam_max = max(lam_max, lam[c])
    never = 1 << 30
    cap = 2 * total + 64
    ts = np.empty(cap)
    known = np.full(cap, never, np.int64)  # smallest level whose margins the state kept
    stamp = np.full(cap, -1, np.int64)
    for i in range(total):
        ts[i] = i / n
    for w in range(total):
        if out[w]:
            known[order[w]] = 0
    e0s, e1s = np.empty(n, np.int64), np.empty(n, np.int64)
    count = 0
    for i in range(n):
        if known[i] > 0 or known[i + 1] > 0:
            e0s[count], e1s[count] = i, i + 1
            count += 1
    stored = total
    level = 0
    evals = 0
    while count > 0:
        level += 1
        scale = 1.0 / (2.0 * n * 2.0 ** level)
        if evals + 2 * count > max_evals or lam_max * scale < 1e-9:
            return False, evals
        margins = _clearances(lam, scale, G, clearance, self_clearance)
        if stored + count > cap:
            cap = 2 * (stored + count)
            ts2, known2, stamp2 = np.empty(cap), np.full(cap, never, np.int64), np.full(cap, -1, np.int64)
            ts2[:stored], known2[:stored], stamp2[:stored] = ts[:stored], known[:stored], stamp[:stored]
            ts, known, stamp = ts2, known2, stamp2
        # this level's states: the midpoints, then the ends that have not kept its margins yet
        check = np.empty(3 * count, np.int64)
        k = 0
        for r in range(count):
            mid = stored + r
            ts[mid] = 0.5 * (ts[e0s[r]] + ts[e1s[r]])
            check[k] = mid
            k += 1
        for r in range(count):
            for e in (e0s[r], e1s[r]):
                if known[e] > level and stamp[e] != level:
                    stamp[e] = level
                    check[k] = e
                    k += 1
        QE = np.empty((nq, k))
        for w in range(k):
            t = ts[check[w]]
            for j in range(nq):
                QE[j, w] = qa[j] + t * (qb[j] - qa[j])
        kept = np.empty(k, np.bool_)
        answer, used = check_blocks(QE, k, (lanes[1], lanes[1]), margins, plain, arrays, ws, kept)
        evals += used
        if answer == COLLISION:
            return False, evals
        for w in range(k):
            if answer == CLEAR or kept[w]:
                known[check[w]] = level
        n0s, n1s = np.empty(2 * count, np.int64), np.empty(2 * count, np.int64)
        c2 = 0
        for r in range(count):
            mid = stored + r
            for a, b in ((e0s[r], mid), (mid, e1s[r])):
                if known[a] > level or known[b] > level:
                    n0s[c2], n1s[c2] = a, b
                    c2 += 1
        stored += count
        e0s, e1s, count = n0s, n1s, c2
    return True, evals


@numba.njit(cache=True)
def _motion(qa, qb, arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, max_margin,
            max_evals, by_values, stats, clock, buf, profile):
    """Whether the straight motion ``qa -> qb`` is **certified** collision-free (``qa`` free).

    Every constraint row ``c`` (a link against the obstacles, a checked link pair) changes
    along the motion no faster than ``Λ_c = Σ_j reach[c, j] |Δq_j|`` per unit of t (the
    Lipschitz bound of :mod:`drake_mh.scene._segment_kernel`, from
    :attr:`~drake_mh.scene.batch.CollisionModel.reach`). A link pair with a floor table
    (:mod:`drake_mh.scene.pair_table`) whose cells along the motion all keep the pair's clearance
    is certified on the whole motion by them (:func:`drake_mh.scene._pair_kernel.segment_floor`):
    its ``Λ_c`` is :data:`CERTIFIED_ROW` and no state checks that pair (its clearance rows are
    ``-inf``: neither its bounding spheres, nor its table, nor its sphere pairs).

    1. ``n`` pieces, ``n >= resolution · |qb - qa|`` and ``n >= max_c Λ_c / (2 max_margin)``;
       the ``n + 1`` states ``t = i / n`` (ends included), in VAMP's "rake" order (``lanes[0]``
       states spread over the whole motion first, so that a collision is found early, then
       blocks of ``lanes[1]``), are checked block by block
       (:func:`drake_mh.scene._state_kernels.check_states`), each row at its clearance raised
       by the margin ``Λ_c / (2 n)`` and, where a sphere is below that, at the plain
       clearance. A state below the plain clearance rejects the motion at once (early exit).
       If every state keeps the margins, every piece is certified, since
       ``V_c(t) >= (V0 + V1 - Λ_c / n) / 2 >= clearance`` on it: most motions that are not
       rejected end here, certified by the boolean check alone.
    2. Otherwise (free, but within the margins somewhere) a bisection decides, with at most
       ``max_evals`` configurations (undecided: rejected): with ``by_values`` None,
       :func:`_refine` (the same bound, batched boolean checks at halving margins), else (any
       other value, e.g. True) the scene's
       :func:`drake_mh.scene._segment_kernel.certify_segments` (the bound on clearance values
       from :func:`~drake_mh.scene._collision_kernels.link_clearances`). The choice is made at
       compile time from the argument's type, so the default (None) does not compile the
       second: 35 s less from an empty numba cache.
    """
    (parent, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = arrays
    t0 = now(clock, buf) if profile else 0.0
    nq = qa.shape[0]
    G, C = g_anchor.shape[0], reach.shape[0]
    d = 0.0
    for j in range(nq):
        d += (qb[j] - qa[j]) ** 2
    d = math.sqrt(d)
    lam = np.empty(C)
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
    QT = np.empty((nq, total))
    order = np.empty(total, np.int64)
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
    margins = _clearances(lam, 1.0 / (2 * n), G, clearance, self_clearance)
    plain = _clearances(lam, 0.0, G, clearance, self_clearance)
    out = np.empty(total, np.bool_)
    answer, used = check_blocks(QT, total, lanes, margins, plain, arrays, ws, out)
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
        certified, evals = _refine(qa, qb, out, order, n, lam, plain, clearance, self_clearance, arrays, ws, lanes,
                                   max_evals)
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


@numba.njit(cache=True)
def _trace(V, P, tree, i):
    """Rows of tree ``tree`` from node ``i`` up to its root, in that order."""
    k, count = i, 0
    while k >= 0:
        count += 1
        k = P[tree, k]
    out = np.empty((count, V.shape[2]))
    k, r = i, 0
    while k >= 0:
        out[r] = V[tree, k]
        r += 1
        k = P[tree, k]
    return out


@numba.njit(cache=True)
def _root(P, tree, i):
    while P[tree, i] >= 0:
        i = P[tree, i]
    return i


@numba.njit(cache=True)
def _drop_collinear(path):
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
def _shortcut(path, iterations, rng, arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, margin,
              max_evals, by_values, stats, clock, buf, profile, start, time_limit):
    """Random shortcutting (Geraerts & Overmars, "Creating high-quality paths for motion
    planning", IJRR 2007): join two random points of the path by a certified straight motion
    (:func:`_motion`) when that is shorter, ``iterations`` times or until the deadline. The
    pieces kept of the old segments are parts of certified segments."""
    t0 = now(clock, buf) if profile else 0.0
    nq = path.shape[1]
    for _ in range(iterations):
        M = path.shape[0]
        if M <= 2 or now(clock, buf) - start > time_limit:
            break
        s = np.zeros(M)
        for k in range(M - 1):
            d = 0.0
            for j in range(nq):
                d += (path[k + 1, j] - path[k, j]) ** 2
            s[k + 1] = s[k] + math.sqrt(d)
        L = s[M - 1]
        u, v = _uniform(rng) * L, _uniform(rng) * L
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
        qa, qb = np.empty(nq), np.empty(nq)
        ha, hb = s[i + 1] - s[i], s[k + 1] - s[k]
        ta = (u - s[i]) / ha if ha > 0 else 0.0
        tb = (v - s[k]) / hb if hb > 0 else 0.0
        for j in range(nq):
            qa[j] = path[i, j] + ta * (path[i + 1, j] - path[i, j])
            qb[j] = path[k, j] + tb * (path[k + 1, j] - path[k, j])
        stats[SHORTCUTS_TRIED] += 1
        if not _motion(qa, qb, arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, margin,
                       max_evals, by_values, stats, clock, buf, profile):
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
    if profile:
        stats[T_SHORTCUT] += now(clock, buf) - t0
    return path


@numba.njit(cache=True)
def plan_kernel(q_start, goals, lower, upper, ints, floats, v_WO, reach, clearance, self_clearance, seed,
                step, resolution, margin, first_lanes, block_lanes, goal_bias, balance, max_nodes, time_limit,
                max_evals, shortcut_iterations, by_values, clock, profile, stats):
    """RRT-Connect (Kuffner & LaValle, "RRT-Connect: An efficient approach to single-query path
    planning", ICRA 2000) from ``q_start`` to any row of ``goals``, then shortcutting.

    One tree grows from the start, one from every goal configuration (all roots of the goal
    tree). Each iteration EXTENDs one tree a ``step`` toward a sample (uniform in the limits,
    or with probability ``goal_bias`` a root of the other tree), then CONNECTs the other tree
    to the new node (repeated ``step`` extensions until reached or blocked); then the trees
    swap (``balance``: the smaller tree grows next, as VAMP does). Every edge is certified by
    :func:`_motion`. The direct motion to each goal (nearest first) is tried before any tree.

    Args:
        seed: ``(1,)`` uint64, the splitmix64 state (advanced in place).
        max_nodes: most nodes added to the trees (the budget), roots not counted.
        time_limit: [s] of the monotonic clock from the start of this call (``inf``: none).
        stats: ``(len(STAT_NAMES),)`` float64, counts and (with ``profile``) seconds, added to.

    Returns:
        ``(path (M, nq), outcome, goal_index)``: ``outcome`` FOUND, BUDGET or TIMEOUT (then
        ``path`` is empty).
    """
    buf = np.zeros(2, np.int64)
    start = now(clock, buf)
    arrays = _unpack(ints, floats)
    lanes = (first_lanes, block_lanes)
    ws = state_workspace(arrays[0].shape[0], arrays[6].shape[0], arrays[11].shape[0], max(first_lanes, block_lanes))
    nq, G = q_start.shape[0], goals.shape[0]
    rng = seed
    empty = np.empty((0, nq))
    # the direct motion, nearest goal first
    dist = np.empty(G)
    for g in range(G):
        acc = 0.0
        for j in range(nq):
            acc += (goals[g, j] - q_start[j]) ** 2
        dist[g] = acc
    for g in np.argsort(dist):
        if _motion(q_start, goals[g], arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, margin,
                   max_evals, by_values, stats, clock, buf, profile):
            path = np.empty((2, nq))
            path[0], path[1] = q_start, goals[g]
            stats[T_TOTAL] += now(clock, buf) - start
            return path, FOUND, g
    cap = max(64, G + 1)
    V = np.empty((2, cap, nq))
    P = np.empty((2, cap), np.int64)
    count = np.zeros(2, np.int64)
    V[0, 0] = q_start
    P[0, 0] = -1
    V[1, :G] = goals
    P[1, :G] = -1
    count[0], count[1] = 1, G
    roots = np.array([1, G], np.int64)
    q_rand, q_new, q = np.empty(nq), np.empty(nq), np.empty(nq)
    a = 0
    added = 0
    while True:
        if now(clock, buf) - start > time_limit:
            stats[T_TOTAL] += now(clock, buf) - start
            stats[NODES] += added
            return empty, TIMEOUT, -1
        if added >= max_nodes:
            stats[T_TOTAL] += now(clock, buf) - start
            stats[NODES] += added
            return empty, BUDGET, -1
        stats[ITERATIONS] += 1
        if max(count[0], count[1]) + 1 >= cap:  # room for this iteration's first node
            cap *= 2
            V2, P2 = np.empty((2, cap, nq)), np.empty((2, cap), np.int64)
            for t in range(2):
                V2[t, :count[t]] = V[t, :count[t]]
                P2[t, :count[t]] = P[t, :count[t]]
            V, P = V2, P2
        b = 1 - a
        t0 = now(clock, buf) if profile else 0.0
        if _uniform(rng) < goal_bias:
            q_rand[:] = V[b, _below(rng, roots[b])]
        else:
            for j in range(nq):
                q_rand[j] = lower[j] + _uniform(rng) * (upper[j] - lower[j])
        if profile:
            t1 = now(clock, buf)
            stats[T_SAMPLE] += t1 - t0
            t0 = t1
        i = _nearest(V[a], count[a], q_rand)
        stats[NN_SCANS] += 1
        _steer(V[a, i], q_rand, step, q_new)
        if profile:
            stats[T_NN] += now(clock, buf) - t0
        if _motion(V[a, i], q_new, arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, margin,
                   max_evals, by_values, stats, clock, buf, profile):
            ia = count[a]
            V[a, ia] = q_new
            P[a, ia] = i
            count[a] += 1
            added += 1
            # CONNECT the other tree to q_new
            t0 = now(clock, buf) if profile else 0.0
            jb = _nearest(V[b], count[b], q_new)
            stats[NN_SCANS] += 1
            if profile:
                stats[T_NN] += now(clock, buf) - t0
            while added < max_nodes:
                if count[b] + 1 >= cap:
                    cap *= 2
                    V2, P2 = np.empty((2, cap, nq)), np.empty((2, cap), np.int64)
                    for t in range(2):
                        V2[t, :count[t]] = V[t, :count[t]]
                        P2[t, :count[t]] = P[t, :count[t]]
                    V, P = V2, P2
                reached = _steer(V[b, jb], q_new, step, q)
                if not _motion(V[b, jb], q, arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution,
                               margin, max_evals, by_values, stats, clock, buf, profile):
                    break
                if reached:  # q_new joins the trees: the path runs through it
                    half_a = _trace(V, P, a, ia)  # q_new ... root of a
                    half_b = _trace(V, P, b, jb)  # node of b next to q_new ... root of b
                    M = half_a.shape[0] + half_b.shape[0]
                    path = np.empty((M, nq))
                    if a == 0:
                        path[:half_a.shape[0]] = half_a[::-1]
                        path[half_a.shape[0]:] = half_b
                        g = _root(P, b, jb)
                    else:
                        path[:half_b.shape[0]] = half_b[::-1]
                        path[half_b.shape[0]:] = half_a
                        g = _root(P, a, ia)
                    stats[NODES] += added
                    path = _drop_collinear(path)
                    path = _shortcut(path, shortcut_iterations, rng, arrays, ws, lanes, v_WO, reach, clearance,
                                     self_clearance, resolution, margin, max_evals, by_values, stats, clock, buf, profile,
                                     start, time_limit)
                    stats[T_TOTAL] += now(clock, buf) - start
                    return path, FOUND, g
                jn = count[b]
                V[b, jn] = q
                P[b, jn] = jb
                count[b] += 1
                added += 1
                jb = jn
                if now(clock, buf) - start > time_limit:
                    break
        if balance:
            a = 0 if count[0] <= count[1] else 1
        else:
            a = 1 - a


@numba.njit(cache=True)
def certify_motions(QA, QB, ints, floats, v_WO, reach, clearance, self_clearance, resolution, margin, first_lanes,
                    block_lanes, max_evals, by_values, clock, stats):
    """``(M,)`` bool: whether each straight motion ``QA[i] -> QB[i]`` (``QA[i]`` free) is certified
    by :func:`_motion`, the planner's check (for tests and other callers)."""
    buf = np.zeros(2, np.int64)
    arrays = _unpack(ints, floats)
    lanes = (first_lanes, block_lanes)
    ws = state_workspace(arrays[0].shape[0], arrays[6].shape[0], arrays[11].shape[0], max(first_lanes, block_lanes))
    out = np.empty(QA.shape[0], np.bool_)
    for i in range(QA.shape[0]):
        out[i] = _motion(QA[i], QB[i], arrays, ws, lanes, v_WO, reach, clearance, self_clearance, resolution, margin,
                         max_evals, by_values, stats, clock, buf, False)
    return out
