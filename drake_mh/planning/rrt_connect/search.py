"""Compiled RRT-Connect: sampling, nearest neighbours, certified motions, shortcutting.

Everything from the first sample to the shortcut path runs in one numba call
(:func:`plan_kernel`); the only Python is the call itself. Every motion (tree edge, direct
connection, shortcut) is certified by :func:`drake_mh.planning.motion.check.certified_motion`.

Randomness: splitmix64 (:mod:`drake_mh._support.random`) on a state array seeded from the caller's
``numpy.random.Generator``: the same seed gives the same path, whatever else runs in the process.
The shortcut and the motion check are shared with ``lazy_prm_star`` (:mod:`drake_mh.planning.motion`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from drake_mh._support.compilation import stable_calls
from drake_mh._support.borrow import borrow
from drake_mh._support.random import below, uniform
from drake_mh.planning.motion import certified_motion, drop_collinear, motion_capacity, now, shortcut, workspaces
from drake_mh.planning.motion.stats import BUDGET, FOUND, ITERATIONS, NN_SCANS, NODES, OUT_OF_DOMAIN, T_FOUND, T_NN, \
    T_SAMPLE, T_TOTAL, TIMEOUT
from drake_mh.scene.kernels import CheckContext, unpack

OPTION_NAMES = ("step", "resolution", "margin", "lanes", "block", "probes", "interior_probes", "goal_bias",
                "balance", "max_certify_evaluations", "shortcut_iterations", "shortcut_min_gain", "clock", "profile",
                "domain_radius")
"""The entries of :func:`plan_kernel`'s ``options`` vector, in order (integers and flags as
float64, exact: the clock's address is below 2**53). One array instead of 15 arguments: numba
unboxes each argument of a call from Python (:mod:`.planner` keeps one vector per config)."""

DOMAIN_MIN_RADIUS, DOMAIN_ALPHA = 1.0, 1e-4
"""Dynamic domain (Yershova, Jaillet, Siméon, LaValle, "Dynamic-Domain RRTs: Efficient
Exploration by Controlling the Sampling Domain", ICRA 2005), with VAMP's constants
(``RRTCSettings``): a node's radius shrinks by ``1 - DOMAIN_ALPHA`` at each further failed
extension, never below ``DOMAIN_MIN_RADIUS`` [rad] (nor below the starting radius), and grows by
``1 + DOMAIN_ALPHA`` at each success."""

SAMPLES_PER_NODE = 1000
"""Most iterations per node of the budget (``max_nodes``): samples that the dynamic domain draws
again add no node, so without this bound a tree whose every node failed, with a small radius,
could sample forever when no deadline is given (VAMP bounds its iterations too)."""

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


@numba.njit(cache=True)
def _grown(V, P, D, count, cap):
    """The trees' arrays (nodes ``V (2, cap, nq)``, parents ``P (2, cap)``, domain radii
    ``D (2, cap)``) copied into arrays of capacity ``cap``."""
    V2, P2, D2 = np.empty((2, cap, V.shape[2])), np.empty((2, cap), np.int64), np.empty((2, cap))
    for t in range(2):
        V2[t, :count[t]] = V[t, :count[t]]
        P2[t, :count[t]] = P[t, :count[t]]
        D2[t, :count[t]] = D[t, :count[t]]
    return V2, P2, D2


@numba.njit(cache=True, inline="always")
def _next_tree(balance, a, count):
    """The tree that grows next: the smaller one (``balance``, VAMP), else the other one."""
    if balance:
        return 0 if count[0] <= count[1] else 1
    return 1 - a


@stable_calls()
@numba.njit(cache=True)
def _out_of_domain(q, i_node, V, D, a):
    """Whether sample ``q`` lies beyond the domain radius of its nearest node ``i_node`` of tree
    ``a`` (a node whose extension never failed has radius ``inf``)."""
    radius = D[a, i_node]
    if radius == math.inf:
        return False
    d = 0.0
    for j in range(q.shape[0]):
        d += (q[j] - V[a, i_node, j]) ** 2
    return d > radius * radius


@stable_calls()
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


@stable_calls()
@numba.njit(cache=True)
def _root(P, tree, i):
    while P[tree, i] >= 0:
        i = P[tree, i]
    return i


@numba.njit(cache=True)
def plan_kernel(q_start, goals, lower, upper, ints, floats, v_WO, reach, clearance, self_clearance, seed, max_nodes,
                time_limit, options, by_values, stats):
    """RRT-Connect (Kuffner & LaValle, "RRT-Connect: An efficient approach to single-query path
    planning", ICRA 2000) from ``q_start`` to any row of ``goals``, then shortcutting.

    One tree grows from the start, one from every goal configuration (all roots of the goal
    tree). Each iteration EXTENDs one tree a ``step`` toward a sample (uniform in the limits,
    or with probability ``goal_bias`` a root of the other tree), then CONNECTs the other tree
    to the new node (repeated ``step`` extensions until reached or blocked); then the trees
    swap (``balance``: the smaller tree grows next, as VAMP does). Every edge is certified by
    :func:`drake_mh.planning.motion.check.certified_motion`. The direct motion to each goal (nearest first) is tried before any tree.

    With a ``domain_radius`` (dynamic domain, :data:`DOMAIN_MIN_RADIUS`), a node whose extension
    failed takes that radius, and a sample farther than its nearest node's radius from it is
    drawn again without any check (VAMP's RRT-Connect does the same): nodes next to obstacles
    stop spending collision checks on samples behind those obstacles.

    Args:
        seed: uint64, the splitmix64 state to start from.
        options: ``(15,)`` float64, the values of :data:`OPTION_NAMES` (the planner's options,
            ``clock`` the address of :func:`drake_mh.planning.motion.clock.clock_address`, ``profile`` 0 or 1).
        by_values: None (the batched check's refinement) or True (the bisection on clearance
            values), :func:`drake_mh.planning.motion.check.certified_motion`'s; a compile-time choice.
        max_nodes: most nodes added to the trees (the budget), roots not counted; and at most
            :data:`SAMPLES_PER_NODE` times as many iterations.
        time_limit: [s] of the monotonic clock from the start of this call (``inf``: none).
        stats: ``(len(STAT_NAMES),)`` float64, set to the counts, ``t_total``, ``t_found`` (when
            the first certified path was found, before the shortcut) and (with ``profile``) the
            other seconds.

    Returns:
        ``(path (M, nq), outcome, goal_index)``: ``outcome`` FOUND, BUDGET or TIMEOUT (then
        ``path`` is empty).
    """
    step, resolution, margin = options[0], options[1], options[2]
    first_lanes, block_lanes, probes, interior = int(options[3]), int(options[4]), int(options[5]), int(options[6])
    goal_bias, balance, max_evals = options[7], options[8] != 0.0, int(options[9])
    shortcut_iterations, shortcut_min_gain, clock, profile = int(options[10]), options[11], int(options[12]), \
        options[13] != 0.0
    domain_radius = options[14]
    buf = np.zeros(2, np.int64)
    start = now(clock, buf)
    stats[:] = 0.0
    state = np.empty(1, np.uint64)
    state[0] = seed
    arrays = unpack(borrow(ints), borrow(floats))  # held by the caller: no reference counts (drake_mh._support.borrow)
    capacity = motion_capacity(upper - lower, reach, resolution, margin)
    owner = workspaces(arrays, q_start.shape[0], reach.shape[0], max(first_lanes, block_lanes), capacity, probes,
                       interior, clearance, self_clearance)
    return _plan(owner, buf, start, arrays, q_start, goals, lower, upper, v_WO, reach,
                 clearance, self_clearance, state, step, resolution, margin, first_lanes, block_lanes, goal_bias,
                 balance, max_nodes, time_limit, max_evals, shortcut_iterations, shortcut_min_gain, by_values, clock,
                 profile, stats, domain_radius)


@numba.njit(cache=True)
def _plan(owner, buf_owner, start, arrays, q_start, goals, lower, upper, v_WO_owner, reach_owner, clearance,
          self_clearance, seed, step, resolution, margin, first_lanes, block_lanes, goal_bias, balance, max_nodes,
          time_limit, max_evals, shortcut_iterations, shortcut_min_gain, by_values, clock, profile, stats_owner,
          domain_radius):
    """:func:`plan_kernel` on its workspace ``owner``. The arrays that every motion passes on are
    borrowed from the arguments (held by the caller for the whole call: :mod:`drake_mh._support.borrow`)."""
    (ws, mws), buf, v_WO, reach, stats = borrow((owner, buf_owner, v_WO_owner, reach_owner, stats_owner))
    ctx = CheckContext(arrays, ws, mws)  # one pointer for every call below (drake_mh.scene.kernels.context)
    lanes = (first_lanes, block_lanes)
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
        if certified_motion(q_start, goals[g], ctx, lanes, v_WO, reach, clearance, self_clearance,
                            resolution, margin, max_evals, by_values, stats, clock, buf, profile, True):
            path = np.empty((2, nq))
            path[0], path[1] = q_start, goals[g]
            stats[T_TOTAL] += now(clock, buf) - start
            stats[T_FOUND] = stats[T_TOTAL]
            return path, FOUND, g
    cap = max(64, G + 1)
    V = np.empty((2, cap, nq))
    P = np.empty((2, cap), np.int64)
    D = np.full((2, cap), np.inf)  # domain radii (inf: no failed extension yet)
    domain_floor = min(DOMAIN_MIN_RADIUS, domain_radius)
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
        if added >= max_nodes or stats[ITERATIONS] >= SAMPLES_PER_NODE * max_nodes:
            stats[T_TOTAL] += now(clock, buf) - start
            stats[NODES] += added
            return empty, BUDGET, -1
        stats[ITERATIONS] += 1
        if max(count[0], count[1]) + 1 >= cap:  # room for this iteration's first node
            cap *= 2
            V, P, D = _grown(V, P, D, count, cap)
        b = 1 - a
        t0 = now(clock, buf) if profile else 0.0
        biased = uniform(rng) < goal_bias
        if biased:
            q_rand[:] = V[b, below(rng, roots[b])]
        else:
            for j in range(nq):
                q_rand[j] = lower[j] + uniform(rng) * (upper[j] - lower[j])
        if profile:
            t1 = now(clock, buf)
            stats[T_SAMPLE] += t1 - t0
            t0 = t1
        i = _nearest(V[a], count[a], q_rand)
        stats[NN_SCANS] += 1
        if domain_radius > 0.0 and _out_of_domain(q_rand, i, V, D, a):
            stats[OUT_OF_DOMAIN] += 1
            if profile:
                stats[T_NN] += now(clock, buf) - t0
            a = _next_tree(balance, a, count)
            continue
        reached = _steer(V[a, i], q_rand, step, q_new)
        if profile:
            stats[T_NN] += now(clock, buf) - t0
        # a motion that ends on a node (a root of the other tree, or q_new below) has both ends free: its
        # probes are inside it (drake_mh.planning.motion.check.INTERIOR_PROBES)
        if certified_motion(V[a, i], q_new, ctx, lanes, v_WO, reach, clearance, self_clearance, resolution,
                            margin, max_evals, by_values, stats, clock, buf, profile, biased and reached):
            ia = count[a]
            V[a, ia] = q_new
            P[a, ia] = i
            D[a, ia] = np.inf
            D[a, i] *= 1.0 + DOMAIN_ALPHA  # (inf stays inf)
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
                    V, P, D = _grown(V, P, D, count, cap)
                reached = _steer(V[b, jb], q_new, step, q)
                if not certified_motion(V[b, jb], q, ctx, lanes, v_WO, reach, clearance, self_clearance,
                                        resolution, margin, max_evals, by_values, stats, clock, buf, profile, reached):
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
                    stats[T_FOUND] = now(clock, buf) - start  # the first certified path, before the shortcut
                    path = drop_collinear(path)
                    path = shortcut(path, shortcut_iterations, shortcut_min_gain, rng, ctx, lanes, v_WO,
                                    reach, clearance, self_clearance, resolution, margin, max_evals, by_values, stats,
                                    clock, buf, profile, start, time_limit)
                    stats[T_TOTAL] += now(clock, buf) - start
                    return path, FOUND, g
                jn = count[b]
                V[b, jn] = q
                P[b, jn] = jb
                D[b, jn] = np.inf
                count[b] += 1
                added += 1
                jb = jn
                if now(clock, buf) - start > time_limit:
                    break
        elif domain_radius > 0.0:  # the extension failed: the node's domain shrinks
            D[a, i] = domain_radius if D[a, i] == math.inf else max(D[a, i] * (1.0 - DOMAIN_ALPHA), domain_floor)
        a = _next_tree(balance, a, count)


@numba.njit(cache=True)
def certify_motions(QA, QB, ints, floats, v_WO, reach, clearance, self_clearance, resolution, margin, first_lanes,
                    block_lanes, probes, max_evals, by_values, clock, stats):
    """``(M,)`` bool: whether each straight motion ``QA[i] -> QB[i]`` (``QA[i]`` free) is certified
    by :func:`drake_mh.planning.motion.check.certified_motion`, the planner's check (for tests and other callers)."""
    buf = np.zeros(2, np.int64)
    arrays = unpack(borrow(ints), borrow(floats))  # held by the caller: no reference counts (drake_mh._support.borrow)
    span = np.zeros(QA.shape[1])
    for i in range(QA.shape[0]):
        for j in range(QA.shape[1]):
            span[j] = max(span[j], abs(QB[i, j] - QA[i, j]))
    capacity = motion_capacity(span, reach, resolution, margin)
    owner = workspaces(arrays, QA.shape[1], reach.shape[0], max(first_lanes, block_lanes), capacity, probes, 0,
                       clearance, self_clearance)
    return _certify_all(owner, buf, arrays, QA, QB, v_WO, reach, clearance, self_clearance, resolution, margin,
                        (first_lanes, block_lanes), max_evals, by_values, clock, stats)


@numba.njit(cache=True)
def _certify_all(owner, buf_owner, arrays, QA, QB, v_WO_owner, reach_owner, clearance, self_clearance, resolution,
                 margin, lanes, max_evals, by_values, clock, stats_owner):
    """:func:`certify_motions` on its workspace ``owner`` (borrowed as in :func:`_plan`)."""
    (ws, mws), buf, v_WO, reach, stats = borrow((owner, buf_owner, v_WO_owner, reach_owner, stats_owner))
    ctx = CheckContext(arrays, ws, mws)
    out = np.empty(QA.shape[0], np.bool_)
    for i in range(QA.shape[0]):
        out[i] = certified_motion(QA[i], QB[i], ctx, lanes, v_WO, reach, clearance, self_clearance,
                                  resolution, margin, max_evals, by_values, stats, clock, buf, False, False)
    return out
