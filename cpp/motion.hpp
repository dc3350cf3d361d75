// Certified straight motions of drake_mh/planning/motion/check.py (certified_motion with
// by_values None: probes, the first pass at margins, _refine; the pair tables' walk is
// spheres.hpp's segment_floor). The same steps in the same order, so the same answers and
// statistics. The clock: std::chrono::steady_clock.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include "states.hpp"

namespace dmh {

// drake_mh/planning/motion/stats.py: indices of the statistics array, counts then seconds
enum Stat {
    ITERATIONS, NODES, NN_SCANS, MOTIONS, STATES, BY_MARGIN, REFINED, REFINE_EVALS, REJECTED, BY_PROBES,
    SHORTCUTS_TRIED, SHORTCUTS_KEPT, OUT_OF_DOMAIN, T_SAMPLE, T_NN, T_CHECK, T_CERTIFY, T_SHORTCUT, T_TOTAL,
    T_FOUND, NSTATS
};
constexpr int FOUND = 0, BUDGET = 1, TIMEOUT = 2;
constexpr double CERTIFIED_ROW = -1.0;  // Λ_c of a row certified on the whole motion
constexpr int64_t LOWEST = 4;           // drake_mh.scene.pair_table.LOWEST: a table's lowest floor
constexpr double PROBES[8] = {1.0, 0.5, 0.25, 0.125, 0.0625, 0.75, 0.375, 0.875};
constexpr double INTERIOR_PROBES[8] = {0.5, 0.25, 0.75, 0.125, 0.875, 0.375, 0.625, 0.0625};

// Seconds of the monotonic clock (only differences are used).
inline double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// From here on no multiply-add is fused (numba compiles check.py, shortcut.py and search.py
// without fast-math): the same roundings as the kernels, so that a motion steered to exactly
// `step` gets the same number of states (ceil of its length times the resolution).
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")

// The options of a plan's motion checks (certified_motion's arguments that stay fixed).
struct MotionOptions {
    double clearance = 0.0, self_clearance = 0.0, resolution = 16.0, margin = 0.02;
    int64_t lanes0 = 64, lanes1 = 64, probes = 4, interior = 4, max_evals = 4096;
    bool profile = false;
};

// certified_motion and what it needs: the scene, the sphere model's reach (C, nq), the
// workspaces (allocated once, grown where a motion needs more).
class MotionChecker {
public:
    const Packed& s;
    const double* reach;
    int64_t nq, G, C;
    MotionOptions o;
    double* stats = nullptr;
    StateWorkspace ws;

    MotionChecker(const Packed& s_, const double* reach_, int64_t nq_, int64_t C_)
        : s(s_), reach(reach_), nq(nq_), G(s_.G), C(C_) {}

    // The workspaces for these options (check.py workspaces / motion_workspace): the probes'
    // plain rows, every link and every pair but those whose lowest floor keeps self_clearance.
    void configure(const MotionOptions& opts) {
        o = opts;
        const int64_t P = C - G, Lp = std::max(o.probes, o.interior);
        ws.allocate(s, nq, std::max({o.lanes0, o.lanes1, Lp}));
        lam.assign(C, 0.0), inv_lam.assign(C, 0.0), speeds.assign(nq, 0.0);
        margin_link.assign(G, 0.0), margin_pair.assign(P, 0.0), plain_link.assign(G, 0.0), plain_pair.assign(P, 0.0);
        probe_link.assign(G, 0.0), probe_pair.assign(P, 0.0), PT.assign(nq * std::max<int64_t>(Lp, 1), 0.0);
        probe_out.assign(std::max<int64_t>(Lp, 1), 0), probe_tau.assign(std::max<int64_t>(Lp, 1), 0.0);
        std::vector<double> lam0(C, 0.0);
        for (int64_t i = 0; i < P; ++i)
            if (s.t_grid[GRID_COLUMNS * i + LOWEST] >= o.self_clearance + 1e-12) lam0[G + i] = CERTIFIED_ROW;
        clearances(lam0.data(), 0.0, probe_link.data(), probe_pair.data());
    }

    // Whether the straight motion qa -> qb (qa free; interior: qb known free too) is certified
    // collision-free (check.py certified_motion, by_values None; its docstring states the steps).
    bool certified_motion(const double* qa, const double* qb, bool interior) {
        double t0 = o.profile ? now() : 0.0;
        stats[STATES] += interior ? o.interior : o.probes;
        if (probe_collides(qa, qb, interior)) {
            stats[MOTIONS] += 1, stats[REJECTED] += 1, stats[BY_PROBES] += 1;
            if (o.profile) stats[T_CHECK] += now() - t0;
            return false;
        }
        double d = 0.0;
        for (int64_t j = 0; j < nq; ++j) {
            const double e = qb[j] - qa[j];
            d += e * e;
            speeds[j] = std::fabs(e);
        }
        d = std::sqrt(d);
        double lam_max = 0.0;
        for (int64_t c = 0; c < C; ++c) {
            double acc = 0.0;
            for (int64_t j = 0; j < nq; ++j) acc += reach[c * nq + j] * std::fabs(qb[j] - qa[j]);
            if (c >= G && s.t_meta[6 * (c - G)] != 0 &&
                (s.t_grid[GRID_COLUMNS * (c - G) + LOWEST] >= o.self_clearance + 1e-12 ||
                 segment_floor(s, c - G, qa, qb) >= o.self_clearance + 1e-12))
                acc = CERTIFIED_ROW;  // the pair's table certifies it along the whole motion
            lam[c] = acc;
            lam_max = std::max(lam_max, acc);
        }
        const int64_t n = std::max({(int64_t)1, (int64_t)std::ceil(d * o.resolution),
                                    (int64_t)std::ceil(lam_max / (2.0 * o.margin))});
        const int64_t total = n + 1, rakes = (total + o.lanes0 - 1) / o.lanes0;
        if ((int64_t)order.size() < total) {
            QT.resize(nq * total), order.resize(total), out.resize(total), tau.resize(total);
        }
        const int64_t ld = (int64_t)order.size();
        int64_t w = 0;
        for (int64_t r = 0; r < rakes; ++r)  // column w: state i = r + k rakes
            for (int64_t i = r; i < total; i += rakes) {
                const double t = (double)i / (double)n;
                for (int64_t j = 0; j < nq; ++j) QT[j * ld + w] = qa[j] + t * (qb[j] - qa[j]);
                order[w++] = i;
            }
        clearances(lam.data(), 1.0 / (2 * n), margin_link.data(), margin_pair.data());
        clearances(lam.data(), 0.0, plain_link.data(), plain_pair.data());
        for (int64_t c = 0; c < C; ++c) inv_lam[c] = lam[c] > 0.0 ? 1.0 / lam[c] : 0.0;
        std::fill(ws.rows_near.begin(), ws.rows_near.end(), 0);
        int64_t used = 0;
        const int answer = check_blocks(s, QT.data(), ld, total, o.lanes0, o.lanes1, margin_link.data(),
                                        margin_pair.data(), plain_link.data(), plain_pair.data(), inv_lam.data(),
                                        speeds.data(), ws, reinterpret_cast<bool*>(out.data()), tau.data(), used);
        stats[MOTIONS] += 1, stats[STATES] += (double)used;
        if (o.profile) {
            const double t1 = now();
            stats[T_CHECK] += t1 - t0;
            t0 = t1;
        }
        if (answer == COLLISION) {
            stats[REJECTED] += 1;
            return false;
        }
        if (answer == CLEAR) {
            stats[BY_MARGIN] += 1;
            return true;
        }
        for (int64_t c = 0; c < C; ++c)  // a row that kept its margins at every state is certified
            if (!ws.rows_near[c]) lam[c] = CERTIFIED_ROW;
        clearances(lam.data(), 0.0, plain_link.data(), plain_pair.data());
        int64_t evals = 0;
        const bool certified = refine(qa, qb, n, evals);
        stats[REFINED] += 1, stats[REFINE_EVALS] += (double)evals;
        if (o.profile) stats[T_CERTIFY] += now() - t0;
        if (!certified) {
            stats[REJECTED] += 1;
            return false;
        }
        return true;
    }

private:
    std::vector<double> lam, inv_lam, speeds, margin_link, margin_pair, plain_link, plain_pair, probe_link,
        probe_pair, PT, probe_tau, QT, tau;
    std::vector<int64_t> order;
    std::vector<unsigned char> probe_out, out;  // bools, read through bool*
    // _refine's pieces and states, kept between motions
    std::vector<double> ts, tv, Pc, Nx, tm, half_gap, QE, tau_m, rm_link, rm_pair;
    std::vector<unsigned char> kept;

    // link (G,), pair (P,): each row's required clearance plus scale Λ_c (and 1e-12), -inf for a
    // row certified on the whole motion (check.py _clearances).
    void clearances(const double* lam_, double scale, double* link, double* pair) const {
        for (int64_t c = 0; c < C; ++c) {
            if (lam_[c] == CERTIFIED_ROW)
                (c < G ? link[c] : pair[c - G]) = -INF;
            else if (c < G)
                link[c] = o.clearance + scale * lam_[c] + 1e-12;
            else
                pair[c - G] = o.self_clearance + scale * lam_[c] + 1e-12;
        }
    }

    // Whether a probe state collides at the plain clearances (check.py probe_collides).
    bool probe_collides(const double* qa, const double* qb, bool interior) {
        const int64_t probes = interior ? o.interior : o.probes;
        if (probes == 0) return false;
        for (int64_t w = 0; w < probes; ++w) {
            const double t = interior ? INTERIOR_PROBES[w] : PROBES[w];
            for (int64_t j = 0; j < nq; ++j) PT[j * probes + w] = qa[j] + t * (qb[j] - qa[j]);
        }
        return check_states(s, PT.data(), probes, 0, probes, probe_link.data(), probe_pair.data(), probe_link.data(),
                            probe_pair.data(), inv_lam.data(), speeds.data(), ws,
                            reinterpret_cast<bool*>(probe_out.data()), probe_tau.data()) == COLLISION;
    }

    // Conservative advancement from both ends of each uncertain piece (check.py _refine).
    bool refine(const double* qa, const double* qb, int64_t n, int64_t& evals) {
        const int64_t total = n + 1;
        double lam_max = 0.0;
        for (int64_t c = 0; c < C; ++c) lam_max = std::max(lam_max, lam[c]);
        const double half = 0.5 / (double)n;
        ts.resize(total), tv.resize(total);
        for (int64_t w = 0; w < total; ++w) {
            ts[order[w]] = (double)order[w] / (double)n;
            tv[order[w]] = std::min(tau[w], half);
        }
        int64_t cap = 2 * n;
        Pc.resize(4 * cap), Nx.resize(4 * cap);
        int64_t count = 0;
        for (int64_t i = 0; i < n; ++i)
            if ((tv[i] < half || tv[i + 1] < half) && tv[i] + tv[i + 1] < ts[i + 1] - ts[i]) {
                double* r = &Pc[4 * count++];
                r[0] = ts[i], r[1] = tv[i], r[2] = ts[i + 1], r[3] = tv[i + 1];
            }
        tm.resize(cap), half_gap.resize(cap), QE.resize(nq * cap), kept.resize(cap), tau_m.resize(cap);
        rm_link.resize(G), rm_pair.resize(C - G);
        evals = 0;
        while (count > 0) {
            if (2 * count > cap) {  // (rare: the pieces doubled beyond the first round's room)
                cap = 2 * count;
                Pc.resize(4 * cap), Nx.resize(4 * cap);
                tm.resize(cap), half_gap.resize(cap), QE.resize(nq * cap), kept.resize(cap), tau_m.resize(cap);
            }
            double need = 0.0;
            for (int64_t r = 0; r < count; ++r) {
                const double a = Pc[4 * r] + Pc[4 * r + 1], b = Pc[4 * r + 2] - Pc[4 * r + 3];
                tm[r] = 0.5 * (a + b), half_gap[r] = 0.5 * (b - a);
                need = std::max(need, half_gap[r]);
            }
            if (evals + count > o.max_evals || lam_max * need < 1e-9) return false;
            clearances(lam.data(), need, rm_link.data(), rm_pair.data());
            for (int64_t r = 0; r < count; ++r)
                for (int64_t j = 0; j < nq; ++j) QE[j * cap + r] = qa[j] + tm[r] * (qb[j] - qa[j]);
            int64_t used = 0;
            const int answer = check_blocks(s, QE.data(), cap, count, o.lanes1, o.lanes1, rm_link.data(),
                                            rm_pair.data(), plain_link.data(), plain_pair.data(), inv_lam.data(),
                                            speeds.data(), ws, reinterpret_cast<bool*>(kept.data()), tau_m.data(),
                                            used);
            evals += used;
            if (answer == COLLISION) return false;
            int64_t c2 = 0;
            for (int64_t r = 0; r < count; ++r) {
                const double vm = tau_m[r];
                if (vm >= half_gap[r]) continue;  // it certifies half the gap on each side
                double* x = &Nx[4 * c2];
                x[0] = Pc[4 * r], x[1] = Pc[4 * r + 1], x[2] = tm[r], x[3] = vm;
                x[4] = tm[r], x[5] = vm, x[6] = Pc[4 * r + 2], x[7] = Pc[4 * r + 3];
                c2 += 2;
            }
            std::swap(Pc, Nx);
            count = c2;
        }
        return true;
    }
};

#pragma GCC pop_options

}  // namespace dmh
