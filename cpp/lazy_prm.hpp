// Informed lazy PRM* (drake_mh/planning/lazy_prm_star/search.py prm_kernel): batches of samples
// (uniform, then in the informed set of the best path), a k-nearest graph, A* on it, and only the
// edges of the path found certified, lazily; the same draws, graph, searches and answers.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

#include "collision.hpp"
#include "rrt_connect.hpp"

namespace dmh {

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")  // numba compiles search.py without fast-math: its roundings

// statistics after the motion check's (stats.py STAT_NAMES: 20 entries), search.py PRM_STAT_NAMES
constexpr int64_t PRM_BATCHES = NSTATS, PRM_SAMPLES = 21, PRM_FREE_SAMPLES = 22, PRM_PRUNED = 23, PRM_GRAPH_NODES = 24,
                  PRM_SEARCHES = 25, PRM_EDGES_CHECKED = 26, PRM_EDGES_INVALID = 27, PRM_IMPROVEMENTS = NSTATS + 8,
                  PRM_N_STATS = NSTATS + 9;
constexpr int64_t PRM_ATTEMPTS_PER_SAMPLE = 100;

struct PrmOptions {  // search.py OPTION_NAMES (the search's own; the motion checks': MotionOptions)
    int64_t batch = 100;
    double k_scale = 1.0;
    int64_t shortcut_iterations = 32;
    double shortcut_min_gain = 0.05;
};

// The deadline of a search: time_limit seconds from start.
struct Deadline {
    double start, time_limit;
    double elapsed() const { return now() - start; }
    bool past() const { return now() - start > time_limit; }
};

namespace prm {

inline double distance(const double* a, const double* b, int64_t nq) {
    double d = 0.0;
    for (int64_t c = 0; c < nq; ++c) {
        const double e = a[c] - b[c];
        d += e * e;
    }
    return std::sqrt(d);
}

inline double length(const std::vector<double>& path, int64_t M, int64_t nq) {
    double total = 0.0;
    for (int64_t r = 0; r + 1 < M; ++r) total += distance(&path[(r + 1) * nq], &path[r * nq], nq);
    return total;
}

// A standard normal draw (Box-Muller) from the splitmix64 state.
inline double gauss(SplitMix64& rng) {
    const double u = 1.0 - rng.uniform();  // (0, 1]
    const double radius = std::sqrt(-2.0 * std::log(u));
    return radius * std::cos(2.0 * M_PI * rng.uniform());
}

// out: uniform in the prolate hyperspheroid {x : |x - qs| + |x - qg| <= c_best} (Gammell, Barfoot,
// Srinivasa, T-RO 2018, Algorithm 2; search.py _informed).
inline void informed(SplitMix64& rng, const double* qs, const double* qg, double c_best, int64_t n, double* out) {
    double norm = 0.0;
    for (int64_t j = 0; j < n; ++j) {
        out[j] = gauss(rng);
        norm += out[j] * out[j];
    }
    double c_min = 0.0;
    for (int64_t j = 0; j < n; ++j) c_min += (qg[j] - qs[j]) * (qg[j] - qs[j]);
    c_min = std::sqrt(c_min);
    const double scale = std::pow(rng.uniform(), 1.0 / (double)n) / std::sqrt(norm);
    const double conjugate = 0.5 * std::sqrt(std::max(c_best * c_best - c_min * c_min, 0.0));
    out[0] *= scale * 0.5 * c_best;
    for (int64_t j = 1; j < n; ++j) out[j] *= scale * conjugate;
    if (c_min > 1e-12) {  // v = e1 - u, u the unit vector qs -> qg: (I - 2 v v' / v'v) e1 = u
        double vv = 0.0, dot = 0.0;
        for (int64_t j = 0; j < n; ++j) {
            const double v = (j == 0 ? 1.0 : 0.0) - (qg[j] - qs[j]) / c_min;
            vv += v * v;
            dot += v * out[j];
        }
        if (vv > 1e-24) {
            const double f = 2.0 * dot / vv;
            for (int64_t j = 0; j < n; ++j) out[j] -= f * ((j == 0 ? 1.0 : 0.0) - (qg[j] - qs[j]) / c_min);
        }
    }
    for (int64_t j = 0; j < n; ++j) out[j] += 0.5 * (qs[j] + qg[j]);
}

// The graph of every alive node joined to its k nearest alive nodes (either way), CSR: node i's
// neighbours nb[start[i] .. start[i + 1]); false (no edges) past the deadline.
inline bool knn_graph(const std::vector<double>& V, const std::vector<char>& alive, int64_t n, int64_t nq,
                      int64_t k, const Deadline& clock, std::vector<int64_t>& start, std::vector<int64_t>& nb) {
    std::vector<int64_t> ids;
    for (int64_t i = 0; i < n; ++i)
        if (alive[i]) ids.push_back(i);
    const int64_t m = (int64_t)ids.size(), kk = std::max<int64_t>(std::min(k, m - 1), 0);
    start.assign(n + 1, 0);
    nb.clear();
    if (kk == 0) return true;
    std::vector<double> VT(nq * m), row(m), best(kk);
    std::vector<int64_t> near(m * kk);
    for (int64_t a = 0; a < m; ++a)
        for (int64_t c = 0; c < nq; ++c) VT[c * m + a] = V[ids[a] * nq + c];
    std::vector<int64_t>& degree = start;
    for (int64_t a = 0; a < m; ++a) {
        if (clock.past()) {  // O(m^2): a large graph must not overrun the deadline
            start.assign(n + 1, 0);
            return false;
        }
        std::fill(row.begin(), row.end(), 0.0);
        for (int64_t c = 0; c < nq; ++c) {
            const double x = VT[c * m + a];
            const double* t = &VT[c * m];
            for (int64_t b = 0; b < m; ++b) {
                const double e = t[b] - x;
                row[b] += e * e;
            }
        }
        row[a] = INFINITY;
        int64_t count = 0;
        int64_t* nr = &near[a * kk];
        for (int64_t b = 0; b < m; ++b) {
            const double d = row[b];
            int64_t r;
            if (count < kk) {
                r = count++;
            } else if (d < best[kk - 1]) {
                r = kk - 1;
            } else {
                continue;
            }
            while (r > 0 && best[r - 1] > d) {  // insertion into the sorted k nearest
                best[r] = best[r - 1], nr[r] = nr[r - 1];
                --r;
            }
            best[r] = d, nr[r] = ids[b];
        }
        for (int64_t r = 0; r < kk; ++r) {
            degree[ids[a] + 1] += 1;
            degree[nr[r] + 1] += 1;
        }
    }
    for (int64_t i = 0; i < n; ++i) start[i + 1] += start[i];
    std::vector<int64_t> fill(start.begin(), start.begin() + n);
    nb.assign(start[n], 0);
    for (int64_t a = 0; a < m; ++a) {
        const int64_t i = ids[a];
        for (int64_t r = 0; r < kk; ++r) {
            const int64_t j = near[a * kk + r];
            nb[fill[i]++] = j;
            nb[fill[j]++] = i;
        }
    }
    return true;
}

inline int64_t edge_key(int64_t i, int64_t j) { return std::min(i, j) * (int64_t(1) << 32) + std::max(i, j); }

inline void block_edge(int64_t i, int64_t j, const std::vector<int64_t>& start, const std::vector<int64_t>& nb,
                       std::vector<char>& blocked) {
    for (int side = 0; side < 2; ++side) {
        const int64_t a = side ? j : i, b = side ? i : j;
        for (int64_t e = start[a]; e < start[a + 1]; ++e)
            if (nb[e] == b) blocked[e] = 1;
    }
}

// A* from node 0 to the nearest reachable goal (nodes 1 .. G), paths shorter than bound only; the
// goal node or -1. Ties of the heap broken by node index, as heapq's tuples.
inline int64_t astar(int64_t n, int64_t G, const std::vector<double>& h, const std::vector<int64_t>& start,
                     const std::vector<int64_t>& nb, const std::vector<double>& weight,
                     const std::vector<char>& blocked, double bound, std::vector<double>& g_cost,
                     std::vector<int64_t>& parent) {
    for (int64_t i = 0; i < n; ++i) g_cost[i] = INFINITY, parent[i] = -1;
    g_cost[0] = 0.0;
    typedef std::pair<double, int64_t> Entry;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
    heap.push(Entry(h[0], 0));
    while (!heap.empty()) {
        const Entry top = heap.top();
        heap.pop();
        const int64_t i = top.second;
        if (top.first > g_cost[i] + h[i]) continue;  // a stale entry
        if (1 <= i && i <= G) return i;
        for (int64_t e = start[i]; e < start[i + 1]; ++e) {
            if (blocked[e]) continue;
            const int64_t j = nb[e];
            const double g = g_cost[i] + weight[e];
            if (g < g_cost[j] && g + h[j] < bound) {
                g_cost[j] = g, parent[j] = i;
                heap.push(Entry(g + h[j], j));
            }
        }
    }
    return -1;
}

}  // namespace prm

// The search (search.py prm_kernel / _search; its docstring states the contract) with the planner's
// motion checks mc (probes, certified motions; stats added to mc.stats) and the batched boolean check
// of the samples (checker). q_start (nq,), goals (G, nq), init_path (M0, nq) (M0 = 0: none) to
// goals[init_goal]. Returns the outcome (FOUND, BUDGET, TIMEOUT); best (M, nq) and best_goal when
// FOUND.
inline int prm_search(MotionChecker& mc, CollisionChecker& checker, SplitMix64& rng, const Deadline& clock,
                      const double* q_start, const double* goals, int64_t G,
                      const double* init_path, int64_t M0, int64_t init_goal, const double* lower,
                      const double* upper, int64_t max_samples, const PrmOptions& o, std::vector<double>& best,
                      int64_t& best_goal) {
    const int64_t nq = mc.nq, batch = o.batch;
    double* stats = mc.stats;
    std::unordered_map<int64_t, int8_t> status;  // edge key -> 1 valid, -1 invalid
    int64_t cap = 1 + G + batch, n = G + 1;
    std::vector<double> V(cap * nq);
    std::vector<char> alive(cap, 1);
    for (int64_t j = 0; j < nq; ++j) V[j] = q_start[j];
    for (int64_t i = 0; i < G * nq; ++i) V[nq + i] = goals[i];
    double c_best = INFINITY, c_graph = INFINITY;
    int64_t M_best = 0;
    best.clear(), best_goal = -1;
    if (M0 >= 2) {
        best.assign(init_path, init_path + M0 * nq);
        M_best = M0, best_goal = init_goal;
        c_best = prm::length(best, M0, nq);
        stats[T_FOUND] = clock.elapsed();
    }
    std::vector<double> Q(batch * nq), h, f_start, weight, g_cost;
    std::vector<char> free(batch), blocked;
    std::vector<int64_t> reachable(G), start_e, nb, parent, nodes;
    int outcome = BUDGET;
    while (true) {
        if (clock.past()) {
            outcome = TIMEOUT;
            break;
        }
        if (stats[PRM_SAMPLES] >= (double)max_samples) break;
        stats[PRM_BATCHES] += 1;  // a batch of samples, informed once a path is known
        int64_t drawn = 0, attempts = 0;
        while (drawn < batch && stats[PRM_SAMPLES] + drawn < (double)max_samples &&
               attempts < PRM_ATTEMPTS_PER_SAMPLE * batch) {
            ++attempts;
            double* qd = &Q[drawn * nq];
            if (c_best < INFINITY) {
                int64_t count = 0;
                for (int64_t g = 0; g < G; ++g)
                    if (prm::distance(&V[0], &V[(1 + g) * nq], nq) < c_best) reachable[count++] = g;
                if (count == 0) break;  // the straight motion to a goal is the path: nothing shorter exists
                const int64_t g = reachable[rng.below(count)];
                prm::informed(rng, q_start, goals + g * nq, c_best, nq, qd);
                bool inside = true;
                for (int64_t j = 0; j < nq; ++j) inside = inside && lower[j] <= qd[j] && qd[j] <= upper[j];
                if (!inside) continue;
            } else {
                for (int64_t j = 0; j < nq; ++j) qd[j] = lower[j] + rng.uniform() * (upper[j] - lower[j]);
            }
            ++drawn;
        }
        stats[PRM_SAMPLES] += (double)drawn;
        if (drawn == 0) break;
        checker.free_batch(Q.data(), drawn, nq, mc.o.clearance, mc.o.self_clearance,
                           reinterpret_cast<bool*>(free.data()));
        if (n + drawn > cap) {
            cap = 2 * (n + drawn);
            V.resize(cap * nq);
            alive.resize(cap, 1);
        }
        for (int64_t b = 0; b < drawn; ++b) {
            if (!free[b]) continue;
            for (int64_t j = 0; j < nq; ++j) V[n * nq + j] = Q[b * nq + j];
            alive[n] = 1;
            ++n;
            stats[PRM_FREE_SAMPLES] += 1;
        }
        h.assign(n, 0.0), f_start.assign(n, 0.0);  // nodes that cannot lie on a shorter path: out of the graph
        for (int64_t i = 0; i < n; ++i) {
            double b = INFINITY;
            for (int64_t g = 1; g <= G; ++g) b = std::min(b, prm::distance(&V[i * nq], &V[g * nq], nq));
            h[i] = b;
            f_start[i] = prm::distance(&V[i * nq], &V[0], nq) + b;
        }
        int64_t graph_nodes = 0;
        for (int64_t i = 0; i < n; ++i) {
            if (i > G && alive[i] && f_start[i] > c_best + 1e-9) {
                alive[i] = 0;
                stats[PRM_PRUNED] += 1;
            }
            graph_nodes += alive[i] ? 1 : 0;
        }
        stats[PRM_GRAPH_NODES] = (double)graph_nodes;
        const int64_t k = (int64_t)std::ceil(o.k_scale * M_E * (1.0 + 1.0 / (double)nq) *
                                             std::log((double)std::max<int64_t>(graph_nodes, 2)));
        prm::knn_graph(V, alive, n, nq, k, clock, start_e, nb);
        weight.assign(nb.size(), 0.0), blocked.assign(nb.size(), 0);
        for (int64_t i = 0; i < n; ++i)
            for (int64_t e = start_e[i]; e < start_e[i + 1]; ++e) {
                const int64_t j = nb[e];
                weight[e] = prm::distance(&V[i * nq], &V[j * nq], nq);
                auto it = status.find(prm::edge_key(i, j));
                blocked[e] = it != status.end() && it->second == -1;
            }
        g_cost.assign(n, 0.0), parent.assign(n, -1);
        while (true) {  // lazy search: certify the shortest path's edges, drop those that fail, search again
            if (clock.past()) break;
            const int64_t goal = prm::astar(n, G, h, start_e, nb, weight, blocked, c_graph - 1e-9, g_cost, parent);
            stats[PRM_SEARCHES] += 1;
            if (goal < 0) break;
            nodes.assign(1, goal);
            while (parent[nodes.back()] >= 0) nodes.push_back(parent[nodes.back()]);
            bool valid = true;
            const int64_t R = (int64_t)nodes.size();
            // the probes of every unknown edge first, then the full check, from the start
            for (int64_t r = R - 1; r > 0; --r) {
                const int64_t i = nodes[r], j = nodes[r - 1], key = prm::edge_key(i, j);
                if (status.count(key) == 0 && mc.probe_collides(&V[i * nq], &V[j * nq], true)) {
                    stats[PRM_EDGES_CHECKED] += 1;
                    status[key] = -1;
                    stats[PRM_EDGES_INVALID] += 1;
                    prm::block_edge(i, j, start_e, nb, blocked);
                    valid = false;
                }
            }
            for (int64_t r = R - 1; r > 0 && valid; --r) {
                const int64_t i = nodes[r], j = nodes[r - 1], key = prm::edge_key(i, j);
                if (status.count(key)) continue;
                stats[PRM_EDGES_CHECKED] += 1;
                if (mc.certified_motion(&V[i * nq], &V[j * nq], true)) {
                    status[key] = 1;
                } else {
                    status[key] = -1;
                    prm::block_edge(i, j, start_e, nb, blocked);
                    stats[PRM_EDGES_INVALID] += 1;
                    valid = false;
                }
            }
            if (!valid) continue;
            c_graph = g_cost[goal];  // the graph's shortest path: shortcut, it may beat the best
            Path found{nq, std::vector<double>(R * nq)};
            for (int64_t r = 0; r < R; ++r)
                for (int64_t j = 0; j < nq; ++j) found.q[r * nq + j] = V[nodes[R - 1 - r] * nq + j];
            found = shortcut(drop_collinear(found), o.shortcut_iterations, o.shortcut_min_gain, rng, mc, clock.start,
                             clock.time_limit);
            const int64_t M = found.rows();
            const double len = prm::length(found.q, M, nq);
            if (len < c_best) {
                if (c_best == INFINITY) stats[T_FOUND] = clock.elapsed();
                c_best = len, best = found.q, M_best = M, best_goal = goal - 1;
                stats[PRM_IMPROVEMENTS] += 1;
            }
            break;
        }
    }
    stats[T_TOTAL] = clock.elapsed();
    if (M_best == 0) {
        best.clear();
        return outcome;
    }
    return FOUND;
}

#pragma GCC pop_options

}  // namespace dmh
