// RRT-Connect of drake_mh/planning/rrt_connect/search.py (plan_kernel / _plan, certify_motions)
// with the shortcut of drake_mh/planning/motion/shortcut.py and the SplitMix64 draws of
// drake_mh/_support/random.py: the same draws in the same order and the same certified motions
// (motion.hpp), so the same seed gives the same path.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "motion.hpp"

namespace dmh {

#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")  // as motion.hpp's MotionChecker: the kernels' roundings

// SplitMix64 (Steele, Lea & Flood, OOPSLA 2014): random.py next_u64 / uniform / below.
struct SplitMix64 {
    uint64_t state;
    uint64_t next() {
        uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        return z ^ (z >> 31);
    }
    double uniform() { return (double)(next() >> 11) * (1.0 / 9007199254740992.0); }
    int64_t below(int64_t n) { return std::min((int64_t)(uniform() * (double)n), n - 1); }
};

// A path (M, nq) row-major.
struct Path {
    int64_t nq = 0;
    std::vector<double> q;
    int64_t rows() const { return (int64_t)q.size() / nq; }
    const double* row(int64_t i) const { return q.data() + i * nq; }
};

// Waypoints on the segment between their neighbours removed (shortcut.py drop_collinear).
inline Path drop_collinear(const Path& path) {
    const int64_t M = path.rows(), nq = path.nq;
    std::vector<char> keep(M, 1);
    int64_t last = 0;
    for (int64_t k = 1; k < M - 1; ++k) {
        const double *a = path.row(last), *b = path.row(k), *c = path.row(k + 1);
        double ab = 0.0, ac = 0.0, dot = 0.0;
        for (int64_t j = 0; j < nq; ++j) {
            ab += (b[j] - a[j]) * (b[j] - a[j]);
            ac += (c[j] - a[j]) * (c[j] - a[j]);
            dot += (b[j] - a[j]) * (c[j] - a[j]);
        }
        if (ab <= ac && ac > 0.0 && dot * dot >= ab * ac * (1.0 - 1e-14) && dot > 0.0)
            keep[k] = 0;
        else
            last = k;
    }
    Path out{nq, {}};
    for (int64_t k = 0; k < M; ++k)
        if (keep[k]) out.q.insert(out.q.end(), path.row(k), path.row(k) + nq);
    return out;
}

// The path's length from its first waypoint to each waypoint (shortcut.py arc_lengths).
inline std::vector<double> arc_lengths(const Path& path) {
    const int64_t M = path.rows();
    std::vector<double> s(M, 0.0);
    for (int64_t k = 0; k + 1 < M; ++k) {
        double d = 0.0;
        const double *a = path.row(k), *b = path.row(k + 1);
        for (int64_t j = 0; j < path.nq; ++j) d += (b[j] - a[j]) * (b[j] - a[j]);
        s[k + 1] = s[k] + std::sqrt(d);
    }
    return s;
}

// Random shortcutting (Geraerts & Overmars, IJRR 2007; shortcut.py shortcut): iterations draws
// or until the deadline, a draw gaining less than min_gain of the length not checked.
inline Path shortcut(Path path, int64_t iterations, double min_gain, SplitMix64& rng, MotionChecker& mc,
                     double start, double time_limit) {
    double* stats = mc.stats;
    const double t0 = mc.o.profile ? now() : 0.0;
    const int64_t nq = path.nq;
    std::vector<double> qa(nq), qb(nq);
    std::vector<double> s = arc_lengths(path);
    for (int64_t it = 0; it < iterations; ++it) {
        const int64_t M = path.rows();
        if (M <= 2 || now() - start > time_limit) break;
        const double L = s[M - 1];
        double u = rng.uniform() * L, v = rng.uniform() * L;
        if (u > v) std::swap(u, v);
        int64_t i = 0;
        while (i < M - 2 && s[i + 1] <= u) ++i;
        int64_t k = i;
        while (k < M - 2 && s[k + 1] <= v) ++k;
        if (k == i) continue;
        const double ha = s[i + 1] - s[i], hb = s[k + 1] - s[k];
        const double ta = ha > 0 ? (u - s[i]) / ha : 0.0, tb = hb > 0 ? (v - s[k]) / hb : 0.0;
        double chord = 0.0;
        for (int64_t j = 0; j < nq; ++j) {
            qa[j] = path.row(i)[j] + ta * (path.row(i + 1)[j] - path.row(i)[j]);
            qb[j] = path.row(k)[j] + tb * (path.row(k + 1)[j] - path.row(k)[j]);
            chord += (qb[j] - qa[j]) * (qb[j] - qa[j]);
        }
        if ((v - u) - std::sqrt(chord) < min_gain * L) continue;
        stats[SHORTCUTS_TRIED] += 1;
        if (!mc.certified_motion(qa.data(), qb.data(), true)) continue;
        stats[SHORTCUTS_KEPT] += 1;
        Path next{nq, {}};  // path[:i+1], qa (unless path[i]), qb (unless path[k+1]), path[k+1:]
        next.q.insert(next.q.end(), path.q.begin(), path.q.begin() + (i + 1) * nq);
        if (ta > 0.0) next.q.insert(next.q.end(), qa.begin(), qa.end());
        if (tb < 1.0) next.q.insert(next.q.end(), qb.begin(), qb.end());
        next.q.insert(next.q.end(), path.q.begin() + (k + 1) * nq, path.q.end());
        path = std::move(next);
        s = arc_lengths(path);
    }
    if (mc.o.profile) stats[T_SHORTCUT] += now() - t0;
    return path;
}

constexpr double DOMAIN_MIN_RADIUS = 1.0, DOMAIN_ALPHA = 1e-4;  // search.py's dynamic domain
constexpr int64_t SAMPLES_PER_NODE = 1000;

// The planner's options (search.py OPTION_NAMES, those read here).
struct PlanOptions {
    double step = 1.5, goal_bias = 0.05, shortcut_min_gain = 0.05, domain_radius = 4.0;
    bool balance = true;
    int64_t shortcut_iterations = 32;
};

struct PlanResult {
    Path path;
    int outcome = BUDGET;
    int64_t goal = -1;
};

// RRT-Connect from q_start to any row of goals (G, nq), then shortcutting (search.py
// plan_kernel; its docstring states the contract). stats (NSTATS,) is set.
inline PlanResult rrt_connect(MotionChecker& mc, const PlanOptions& po, const double* q_start, const double* goals,
                              int64_t G, const double* lower, const double* upper, uint64_t seed, int64_t max_nodes,
                              double time_limit) {
    double* stats = mc.stats;
    const int64_t nq = mc.nq;
    const bool profile = mc.o.profile;
    const double start = now();
    std::fill(stats, stats + NSTATS, 0.0);
    SplitMix64 rng{seed};
    PlanResult result;
    result.path.nq = nq;
    std::vector<double> dist(G);
    for (int64_t g = 0; g < G; ++g) {
        double acc = 0.0;
        for (int64_t j = 0; j < nq; ++j) acc += (goals[g * nq + j] - q_start[j]) * (goals[g * nq + j] - q_start[j]);
        dist[g] = acc;
    }
    std::vector<int64_t> by_distance(G);
    std::iota(by_distance.begin(), by_distance.end(), 0);
    std::stable_sort(by_distance.begin(), by_distance.end(), [&](int64_t x, int64_t y) { return dist[x] < dist[y]; });
    for (int64_t g : by_distance) {  // the direct motion, nearest goal first
        if (mc.certified_motion(q_start, goals + g * nq, true)) {
            result.path.q.assign(q_start, q_start + nq);
            result.path.q.insert(result.path.q.end(), goals + g * nq, goals + (g + 1) * nq);
            stats[T_TOTAL] += now() - start;
            stats[T_FOUND] = stats[T_TOTAL];
            result.outcome = FOUND, result.goal = g;
            return result;
        }
    }
    std::vector<double> V[2], D[2];  // nodes (count, nq), domain radii (inf: no failed extension)
    std::vector<int64_t> P[2];        // parents (-1: a root)
    int64_t count[2] = {1, G};
    for (int t = 0; t < 2; ++t) {
        const int64_t cap = std::max<int64_t>(64, G + 1);
        V[t].resize(cap * nq), D[t].assign(cap, INF), P[t].assign(cap, -1);
    }
    std::copy(q_start, q_start + nq, V[0].begin());
    std::copy(goals, goals + G * nq, V[1].begin());
    const int64_t roots[2] = {1, G};
    auto room = [&](int t) {  // room for one more node in tree t
        if ((count[t] + 1) * nq > (int64_t)V[t].size()) {
            const int64_t cap = 2 * (int64_t)D[t].size();
            V[t].resize(cap * nq), D[t].resize(cap, INF), P[t].resize(cap, -1);
        }
    };
    auto nearest = [&](int t, const double* q) {
        double best = INF;
        int64_t arg = 0;
        for (int64_t i = 0; i < count[t]; ++i) {
            const double* v = V[t].data() + i * nq;
            double d = 0.0;
            for (int64_t j = 0; j < nq; ++j) d += (v[j] - q[j]) * (v[j] - q[j]);
            if (d < best) best = d, arg = i;
        }
        return arg;
    };
    auto steer = [&](const double* qa, const double* qb, double* out) {  // search.py _steer
        double d = 0.0;
        for (int64_t j = 0; j < nq; ++j) d += (qb[j] - qa[j]) * (qb[j] - qa[j]);
        d = std::sqrt(d);
        if (d <= po.step) {
            std::copy(qb, qb + nq, out);
            return true;
        }
        const double f = po.step / d;
        for (int64_t j = 0; j < nq; ++j) out[j] = qa[j] + f * (qb[j] - qa[j]);
        return false;
    };
    auto next_tree = [&](int a) { return po.balance ? (count[0] <= count[1] ? 0 : 1) : 1 - a; };
    auto finish = [&](int outcome, int64_t added) {
        stats[T_TOTAL] += now() - start;
        stats[NODES] += (double)added;
        result.outcome = outcome;
        return result;
    };
    const double domain_floor = std::min(DOMAIN_MIN_RADIUS, po.domain_radius);
    std::vector<double> q_rand(nq), q_new(nq), q(nq);
    int a = 0;
    int64_t added = 0;
    while (true) {
        if (now() - start > time_limit) return finish(TIMEOUT, added);
        if (added >= max_nodes || stats[ITERATIONS] >= (double)(SAMPLES_PER_NODE * max_nodes))
            return finish(BUDGET, added);
        stats[ITERATIONS] += 1;
        room(0), room(1);
        const int b = 1 - a;
        double t0 = profile ? now() : 0.0;
        const bool biased = rng.uniform() < po.goal_bias;
        if (biased) {
            const double* r = V[b].data() + rng.below(roots[b]) * nq;
            std::copy(r, r + nq, q_rand.begin());
        } else {
            for (int64_t j = 0; j < nq; ++j) q_rand[j] = lower[j] + rng.uniform() * (upper[j] - lower[j]);
        }
        if (profile) {
            const double t1 = now();
            stats[T_SAMPLE] += t1 - t0;
            t0 = t1;
        }
        const int64_t i = nearest(a, q_rand.data());
        stats[NN_SCANS] += 1;
        if (po.domain_radius > 0.0 && D[a][i] != INF) {  // the sample beyond its nearest node's domain
            double d = 0.0;
            for (int64_t j = 0; j < nq; ++j) d += (q_rand[j] - V[a][i * nq + j]) * (q_rand[j] - V[a][i * nq + j]);
            if (d > D[a][i] * D[a][i]) {
                stats[OUT_OF_DOMAIN] += 1;
                if (profile) stats[T_NN] += now() - t0;
                a = next_tree(a);
                continue;
            }
        }
        bool reached = steer(V[a].data() + i * nq, q_rand.data(), q_new.data());
        if (profile) stats[T_NN] += now() - t0;
        if (mc.certified_motion(V[a].data() + i * nq, q_new.data(), biased && reached)) {
            const int64_t ia = count[a];
            std::copy(q_new.begin(), q_new.end(), V[a].begin() + ia * nq);
            P[a][ia] = i, D[a][ia] = INF;
            D[a][i] *= 1.0 + DOMAIN_ALPHA;
            count[a] += 1, added += 1;
            t0 = profile ? now() : 0.0;  // CONNECT the other tree to q_new
            int64_t jb = nearest(b, q_new.data());
            stats[NN_SCANS] += 1;
            if (profile) stats[T_NN] += now() - t0;
            while (added < max_nodes) {
                room(b);
                reached = steer(V[b].data() + jb * nq, q_new.data(), q.data());
                if (!mc.certified_motion(V[b].data() + jb * nq, q.data(), reached)) break;
                if (reached) {  // q_new joins the trees: the path runs through it
                    auto trace = [&](int t, int64_t k) {  // node k ... the root of tree t
                        std::vector<int64_t> rows;
                        for (; k >= 0; k = P[t][k]) rows.push_back(k);
                        return rows;
                    };
                    const std::vector<int64_t> half_a = trace(a, ia), half_b = trace(b, jb);
                    const std::vector<int64_t>& first = a == 0 ? half_a : half_b;
                    const std::vector<int64_t>& second = a == 0 ? half_b : half_a;
                    const int t_first = a == 0 ? a : b, t_second = a == 0 ? b : a;
                    Path path{nq, {}};
                    for (auto k = first.rbegin(); k != first.rend(); ++k)
                        path.q.insert(path.q.end(), V[t_first].begin() + *k * nq, V[t_first].begin() + (*k + 1) * nq);
                    for (int64_t k : second)
                        path.q.insert(path.q.end(), V[t_second].begin() + k * nq, V[t_second].begin() + (k + 1) * nq);
                    result.goal = a == 0 ? half_b.back() : half_a.back();  // the root in the goal tree
                    stats[NODES] += (double)added;
                    stats[T_FOUND] = now() - start;  // the first certified path, before the shortcut
                    result.path = shortcut(drop_collinear(path), po.shortcut_iterations, po.shortcut_min_gain, rng,
                                           mc, start, time_limit);
                    stats[T_TOTAL] += now() - start;
                    result.outcome = FOUND;
                    return result;
                }
                const int64_t jn = count[b];
                std::copy(q.begin(), q.end(), V[b].begin() + jn * nq);
                P[b][jn] = jb, D[b][jn] = INF;
                count[b] += 1, added += 1;
                jb = jn;
                if (now() - start > time_limit) break;
            }
        } else if (po.domain_radius > 0.0) {  // the extension failed: the node's domain shrinks
            D[a][i] = D[a][i] == INF ? po.domain_radius : std::max(D[a][i] * (1.0 - DOMAIN_ALPHA), domain_floor);
        }
        a = next_tree(a);
    }
}

#pragma GCC pop_options

}  // namespace dmh
