"""Compiled informed lazy PRM*: batches of samples, a k-nearest graph, lazily certified edges.

:func:`prm_kernel` runs the whole search in one numba call. Each batch draws samples (uniform in
the joint limits until a path is known, then in its informed set), keeps the free ones as nodes,
drops the nodes that cannot lie on a shorter path, connects every node to its
``k = k_scale · e (1 + 1/d) log n`` nearest (Karaman & Frazzoli, "Sampling-based algorithms for
optimal motion planning", IJRR 2011: PRM*), and searches the graph for the shortest path (A*,
joint-space length, the distance to the nearest goal as heuristic), certifying only the edges of
the path it finds (lazy PRM: Bohlin & Kavraki, ICRA 2000): first the probe states of all of its
unknown edges, then each edge whole, from the start; an edge that fails is removed and the search
repeated. A new shortest path of the graph is shortcut and replaces the best path if shorter.
Every edge of a returned path is certified by the planner's motion check
(:func:`drake_mh.planning.motion.check.certified_motion`).

Informed sampling (Gammell, Barfoot, Srinivasa, "Informed sampling for asymptotically optimal
path planning", T-RO 2018): once a path of length ``c`` is known, only configurations ``x`` with
``|x - q_start| + |x - q_goal| <= c`` can lie on a shorter one; they are drawn uniformly from
that prolate hyperspheroid (of a goal chosen at random among those it can still reach shorter).
"""

from __future__ import annotations

import heapq
import math

import numba
import numpy as np
from numba.core import types
from numba.typed import Dict

from drake_mh._support.borrow import borrow
from drake_mh._support.random import below, uniform
from drake_mh.planning.motion import (certified_motion, drop_collinear, motion_capacity, now, probe_collides,
                                      shortcut, workspaces)
from drake_mh.planning.motion.stats import BUDGET, FOUND, STAT_NAMES, T_FOUND, T_TOTAL, TIMEOUT
from drake_mh.scene.kernels import CheckContext, collision_free, unpack

PRM_STAT_NAMES = ("batches", "samples", "free_samples", "pruned", "graph_nodes", "searches", "edges_checked",
                  "edges_invalid", "improvements")
"""Statistics of the search, after the motion check's (:data:`~drake_mh.planning.motion.stats.STAT_NAMES`,
whose counts the check adds to): ``graph_nodes`` the nodes of the last graph searched."""
_N0 = len(STAT_NAMES)
BATCHES, SAMPLES, FREE_SAMPLES, PRUNED, GRAPH_NODES, SEARCHES, EDGES_CHECKED, EDGES_INVALID, IMPROVEMENTS = \
    range(_N0, _N0 + len(PRM_STAT_NAMES))
N_STATS = _N0 + len(PRM_STAT_NAMES)

OPTION_NAMES = ("batch", "k_scale", "resolution", "margin", "lanes", "block", "probes", "interior_probes",
                "max_certify_evaluations", "shortcut_iterations", "shortcut_min_gain", "clock")
"""The entries of :func:`prm_kernel`'s ``options`` vector, in order."""

ATTEMPTS_PER_SAMPLE = 100
"""Most informed draws per sample kept in a batch (draws outside the joint limits are drawn
again): a batch whose informed set lies almost wholly outside the limits ends short."""

_KEY = 1 << 32
"""Edge ``(i, j)``, ``i < j``, is the key ``i · _KEY + j`` of the edges' states."""
VALID, INVALID = np.int8(1), np.int8(-1)


@numba.njit(cache=True)
def _gauss(rng):
    """A standard normal draw (Box-Muller) from the splitmix64 state ``rng``."""
    u = 1.0 - uniform(rng)  # (0, 1]
    return math.sqrt(-2.0 * math.log(u)) * math.cos(2.0 * math.pi * uniform(rng))


@numba.njit(cache=True)
def _informed(rng, qs, qg, c_best, out):
    """``out``: uniform in the prolate hyperspheroid ``{x : |x - qs| + |x - qg| <= c_best}``
    (Gammell et al. 2018, Algorithm 2): a point of the unit ball, scaled by the transverse
    ``c_best / 2`` and conjugate ``sqrt(c_best² - c_min²) / 2`` radii, turned so that its
    first axis runs from ``qs`` to ``qg`` (a Householder reflection: the hyperspheroid is
    symmetric, so any orthogonal map that does it will do), centred between them."""
    n = qs.shape[0]
    norm = 0.0
    for j in range(n):
        out[j] = _gauss(rng)
        norm += out[j] * out[j]
    c_min = 0.0
    for j in range(n):
        c_min += (qg[j] - qs[j]) ** 2
    c_min = math.sqrt(c_min)
    scale = uniform(rng) ** (1.0 / n) / math.sqrt(norm)
    conjugate = 0.5 * math.sqrt(max(c_best * c_best - c_min * c_min, 0.0))
    out[0] *= scale * 0.5 * c_best
    for j in range(1, n):
        out[j] *= scale * conjugate
    if c_min > 1e-12:  # v = e1 - u, u the unit vector qs -> qg: (I - 2 v v' / v'v) e1 = u
        vv, dot = 0.0, 0.0
        for j in range(n):
            v = (1.0 if j == 0 else 0.0) - (qg[j] - qs[j]) / c_min
            vv += v * v
            dot += v * out[j]
        if vv > 1e-24:
            f = 2.0 * dot / vv
            for j in range(n):
                out[j] -= f * ((1.0 if j == 0 else 0.0) - (qg[j] - qs[j]) / c_min)
    for j in range(n):
        out[j] += 0.5 * (qs[j] + qg[j])


@numba.njit(cache=True)
def _distance(V, i, j):
    d = 0.0
    for c in range(V.shape[1]):
        e = V[i, c] - V[j, c]
        d += e * e
    return math.sqrt(d)


@numba.njit(cache=True)
def _heuristics(V, n, G, h, f_start):
    """``h[i]``: distance of node ``i`` to the nearest goal (nodes ``1 .. G``); ``f_start[i]``:
    ``|V[i] - V[0]| + h[i]``, the length of the shortest path through node ``i``, at least."""
    for i in range(n):
        best = math.inf
        for g in range(1, G + 1):
            best = min(best, _distance(V, i, g))
        h[i] = best
        f_start[i] = _distance(V, i, 0) + best


@numba.njit(cache=True)
def _knn_graph(V, alive, n, k, clock, buf, start_time, time_limit):
    """The graph of every alive node joined to its ``k`` nearest alive nodes (either way):
    ``(start (n + 1,), neighbours)``, node ``i``'s neighbours ``neighbours[start[i]:start[i + 1]]``
    (a pair nearest to each other appears twice: the search does not mind). The distances of a
    node to all others in one pass over the transposed nodes (SIMD), then the ``k`` smallest by
    insertion (rare after the first ``k``). Past the deadline (read once per node) it returns
    a graph without edges."""
    ids = np.nonzero(alive[:n])[0]
    m, nq = ids.shape[0], V.shape[1]
    kk = max(min(k, m - 1), 0)
    VT = np.empty((nq, m))
    for a in range(m):
        for c in range(nq):
            VT[c, a] = V[ids[a], c]
    near = np.empty((m, max(kk, 1)), np.int64)
    best = np.empty(max(kk, 1))
    row = np.empty(m)
    degree = np.zeros(n + 1, np.int64)
    for a in range(m if kk > 0 else 0):
        if now(clock, buf) - start_time > time_limit:  # O(m^2): a large graph must not overrun the deadline
            return np.zeros(n + 1, np.int64), np.empty(0, np.int64)
        row[:] = 0.0
        for c in range(nq):
            x = VT[c, a]
            for b in range(m):
                e = VT[c, b] - x
                row[b] += e * e
        row[a] = math.inf
        count = 0
        for b in range(m):
            d = row[b]
            if count < kk:
                r = count
                count += 1
            elif d < best[kk - 1]:
                r = kk - 1
            else:
                continue
            while r > 0 and best[r - 1] > d:  # insertion into the sorted k nearest
                best[r], near[a, r] = best[r - 1], near[a, r - 1]
                r -= 1
            best[r], near[a, r] = d, ids[b]
        i = ids[a]
        for r in range(kk):
            degree[i + 1] += 1
            degree[near[a, r] + 1] += 1
    start = np.cumsum(degree)
    fill = start[:n].copy()
    neighbours = np.empty(start[n], np.int64)
    for a in range(m if kk > 0 else 0):
        i = ids[a]
        for r in range(kk):
            j = near[a, r]
            neighbours[fill[i]], neighbours[fill[j]] = j, i
            fill[i] += 1
            fill[j] += 1
    return start, neighbours


@numba.njit(cache=True)
def _edge_arrays(V, start, neighbours, status):
    """``(weight, blocked)`` of each entry of the graph's ``neighbours``: the edge's length [rad]
    and whether it is known invalid (``status``); the search reads these instead of computing
    a distance and looking up a hash table per edge."""
    weight, blocked = np.empty(neighbours.shape[0]), np.zeros(neighbours.shape[0], np.bool_)
    for i in range(start.shape[0] - 1):
        for e in range(start[i], start[i + 1]):
            j = neighbours[e]
            weight[e] = _distance(V, i, j)
            blocked[e] = status.get(min(i, j) * _KEY + max(i, j), np.int8(0)) == INVALID
    return weight, blocked


@numba.njit(cache=True)
def _block(i, j, start, neighbours, blocked):
    """Mark every entry of the edge ``(i, j)`` blocked (both directions)."""
    for a, b in ((i, j), (j, i)):
        for e in range(start[a], start[a + 1]):
            if neighbours[e] == b:
                blocked[e] = True


@numba.njit(cache=True)
def _astar(n, G, h, start, neighbours, weight, blocked, bound, g_cost, parent):
    """A* from node 0 to the nearest reachable goal (nodes ``1 .. G``) over the edges not
    ``blocked``, with paths shorter than ``bound`` only; returns the goal node (``-1``: none),
    the path's nodes by ``parent``."""
    for i in range(n):
        g_cost[i], parent[i] = math.inf, -1
    g_cost[0] = 0.0
    heap = [(h[0], np.int64(0))]
    while len(heap) > 0:
        f, i = heapq.heappop(heap)
        if f > g_cost[i] + h[i]:  # a stale entry
            continue
        if 1 <= i <= G:
            return i
        for e in range(start[i], start[i + 1]):
            if blocked[e]:
                continue
            j = neighbours[e]
            g = g_cost[i] + weight[e]
            if g < g_cost[j] and g + h[j] < bound:
                g_cost[j], parent[j] = g, i
                heapq.heappush(heap, (g + h[j], j))
    return -1


@numba.njit(cache=True)
def prm_kernel(q_start, goals, init_path, init_goal, lower, upper, ints, floats, v_WO, reach, clearance,
               self_clearance, seed, max_samples, time_limit, options, stats):
    """Informed lazy PRM* (module docstring) from ``q_start`` to any row of ``goals``, until
    ``max_samples`` samples or ``time_limit`` seconds.

    ``init_path`` (``(M, nq)`` from ``q_start`` to ``goals[init_goal]``, each edge certified;
    ``M = 0``: none) is the best path to begin with: its length bounds the informed set, but its
    waypoints do not join the graph (a graph holding a path already shortcut would rarely find a
    shorter one through random samples: its own paths zigzag). Each time the graph's shortest
    path shortens, that path is shortcut
    (:func:`~drake_mh.planning.motion.shortcut`, ``shortcut_iterations`` draws)
    and kept if shorter than the best.

    Args:
        seed: uint64, the splitmix64 state.
        options: ``(12,)`` float64, the values of :data:`OPTION_NAMES`.
        stats: ``(N_STATS,)`` float64, set to the counts, ``t_total`` and ``t_found`` (the first
            path: at once with ``init_path``).

    Returns:
        ``(path (M, nq), outcome, goal_index)``, ``outcome`` FOUND, BUDGET or TIMEOUT (the
        latter two with an empty path: no path was found).
    """
    clock = int(options[11])
    buf = np.zeros(2, np.int64)
    start = now(clock, buf)
    stats[:] = 0.0
    state = np.empty(1, np.uint64)
    state[0] = seed
    arrays = unpack(borrow(ints), borrow(floats))  # held by the caller (drake_mh._support.borrow)
    resolution, margin = options[2], options[3]
    lanes = (int(options[4]), int(options[5]))
    capacity = motion_capacity(upper - lower, reach, resolution, margin)
    owner = workspaces(arrays, q_start.shape[0], reach.shape[0], max(lanes[0], lanes[1]), capacity, int(options[6]),
                       int(options[7]), clearance, self_clearance)
    return _search(owner, buf, start, arrays, q_start, goals, init_path, init_goal, lower, upper, v_WO, reach,
                   clearance, self_clearance, state, max_samples, time_limit, options, lanes, stats)


@numba.njit(cache=True)
def _search(owner, buf_owner, start, arrays, q_start, goals, init_path, init_goal, lower, upper, v_WO_owner,
            reach_owner, clearance, self_clearance, rng, max_samples, time_limit, options, lanes, stats_owner):
    """:func:`prm_kernel` on its workspace ``owner`` (the arrays borrowed as in ``rrt_connect``)."""
    (ws, mws), buf, v_WO, reach, stats = borrow((owner, buf_owner, v_WO_owner, reach_owner, stats_owner))
    ctx = CheckContext(arrays, ws, mws)
    (parent_f, KR, Kp, perm, kind, qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius,
     kinds, R_WO, p_WO, dims, o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
     u_offset, u_radius) = arrays
    batch, k_scale = int(options[0]), options[1]
    resolution, margin, max_evals = options[2], options[3], int(options[8])
    shortcut_iterations, shortcut_min_gain, clock = int(options[9]), options[10], int(options[11])
    nq, G = q_start.shape[0], goals.shape[0]
    status = Dict.empty(key_type=types.int64, value_type=types.int8)
    cap = 1 + G + batch
    V = np.empty((cap, nq))
    alive = np.ones(cap, np.bool_)
    V[0] = q_start
    V[1:G + 1] = goals
    n = G + 1
    # the best path (its length bounds the informed set) and the graph's own best length (bounds its search)
    c_best, best, best_goal, c_graph = math.inf, np.empty((0, nq)), -1, math.inf
    if init_path.shape[0] >= 2:
        c_best, best, best_goal = _length(init_path), init_path.copy(), init_goal
        stats[T_FOUND] = now(clock, buf) - start
    QT, free = np.empty((nq, batch)), np.empty(batch, np.bool_)
    q = np.empty(nq)
    reachable = np.empty(G, np.int64)
    outcome = BUDGET
    while True:
        if now(clock, buf) - start > time_limit:
            outcome = TIMEOUT
            break
        if stats[SAMPLES] >= max_samples:
            break
        # a batch of samples, informed once a path is known
        stats[BATCHES] += 1
        drawn, attempts = 0, 0
        while drawn < batch and stats[SAMPLES] + drawn < max_samples and attempts < ATTEMPTS_PER_SAMPLE * batch:
            attempts += 1
            if c_best < math.inf:
                count = 0
                for g in range(G):
                    if _distance(V, 0, 1 + g) < c_best:
                        reachable[count] = g
                        count += 1
                if count == 0:  # the straight motion to a goal is the path: nothing shorter exists
                    attempts = ATTEMPTS_PER_SAMPLE * batch
                    break
                g = reachable[below(rng, count)]
                _informed(rng, q_start, goals[g], c_best, q)
                inside = True
                for j in range(nq):
                    inside = inside and lower[j] <= q[j] <= upper[j]
                if not inside:
                    continue
            else:
                for j in range(nq):
                    q[j] = lower[j] + uniform(rng) * (upper[j] - lower[j])
            QT[:, drawn] = q
            drawn += 1
        stats[SAMPLES] += drawn
        if drawn == 0:
            break
        collision_free(np.ascontiguousarray(QT[:, :drawn]), clearance, self_clearance, parent_f, KR, Kp, perm, kind,
                       qidx, g_anchor, g_offset, g_radius, g_start, s_offset, s_radius, kinds, R_WO, p_WO, dims,
                       o_radius, o_gap, pair_a, pair_b, t_meta, t_grid, t_vals, g_capsule, g_ustart, u_start,
                       u_offset, u_radius, free[:drawn])
        if n + drawn > cap:
            cap = 2 * (n + drawn)
            V2, alive2 = np.empty((cap, nq)), np.ones(cap, np.bool_)
            V2[:n], alive2[:n] = V[:n], alive[:n]
            V, alive = V2, alive2
        for b in range(drawn):
            if free[b]:
                V[n] = QT[:, b]
                alive[n] = True
                n += 1
                stats[FREE_SAMPLES] += 1
        # nodes that cannot lie on a path shorter than the best: out of the graph
        h, f_start = np.empty(n), np.empty(n)
        _heuristics(V, n, G, h, f_start)
        graph_nodes = 0
        for i in range(n):
            if i > G and alive[i] and f_start[i] > c_best + 1e-9:
                alive[i] = False
                stats[PRUNED] += 1
            graph_nodes += alive[i]
        stats[GRAPH_NODES] = graph_nodes
        k = int(math.ceil(k_scale * math.e * (1.0 + 1.0 / nq) * math.log(max(graph_nodes, 2))))
        start_e, neighbours = _knn_graph(V, alive, n, k, clock, buf, start, time_limit)
        weight, blocked = _edge_arrays(V, start_e, neighbours, status)
        g_cost, parent = np.empty(n), np.empty(n, np.int64)
        # lazy search: certify the edges of the shortest path found, drop those that fail, search again
        while True:
            if now(clock, buf) - start > time_limit:
                break
            goal = _astar(n, G, h, start_e, neighbours, weight, blocked, c_graph - 1e-9, g_cost, parent)
            stats[SEARCHES] += 1
            if goal < 0:
                break
            nodes = [goal]
            while parent[nodes[-1]] >= 0:
                nodes.append(parent[nodes[-1]])
            valid = True
            # the probes of every unknown edge first (a few states each: most invalid edges fail there), then
            # the full check, from the start
            for r in range(len(nodes) - 1, 0, -1):
                i, j = nodes[r], nodes[r - 1]
                key = min(i, j) * _KEY + max(i, j)
                if key not in status and probe_collides(V[i], V[j], ctx, True):
                    stats[EDGES_CHECKED] += 1
                    status[key] = INVALID
                    stats[EDGES_INVALID] += 1
                    _block(i, j, start_e, neighbours, blocked)
                    valid = False
            for r in range(len(nodes) - 1, 0, -1):
                if not valid:
                    break
                i, j = nodes[r], nodes[r - 1]
                key = min(i, j) * _KEY + max(i, j)
                if key in status:
                    continue
                stats[EDGES_CHECKED] += 1
                if certified_motion(V[i], V[j], ctx, lanes, v_WO, reach, clearance, self_clearance, resolution,
                                    margin, max_evals, None, stats, clock, buf, False, True):
                    status[key] = VALID
                else:
                    status[key] = INVALID
                    _block(i, j, start_e, neighbours, blocked)
                    stats[EDGES_INVALID] += 1
                    valid = False
                    break
            if valid:  # the graph's shortest path: shortcut, it may beat the best
                c_graph = g_cost[goal]
                found = np.empty((len(nodes), nq))
                for r in range(len(nodes)):
                    found[r] = V[nodes[len(nodes) - 1 - r]]
                found = shortcut(drop_collinear(found), shortcut_iterations, shortcut_min_gain, rng, ctx, lanes,
                                 v_WO, reach, clearance, self_clearance, resolution, margin, max_evals, None, stats,
                                 clock, buf, False, start, time_limit)
                length = _length(found)
                if length < c_best:
                    if c_best == math.inf:
                        stats[T_FOUND] = now(clock, buf) - start
                    c_best, best, best_goal = length, found, goal - 1
                    stats[IMPROVEMENTS] += 1
                break
    stats[T_TOTAL] = now(clock, buf) - start
    if best.shape[0] == 0:
        return best, outcome, -1
    return best, FOUND, best_goal


@numba.njit(cache=True)
def _length(path):
    """The path's joint-space length [rad]."""
    total = 0.0
    for r in range(path.shape[0] - 1):
        d = 0.0
        for j in range(path.shape[1]):
            d += (path[r + 1, j] - path[r, j]) ** 2
        total += math.sqrt(d)
    return total
