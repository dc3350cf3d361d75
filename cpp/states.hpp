// The early-exit state check at two clearances of drake_mh/scene/kernels/states.py
// (check_states, check_blocks): for a block of configurations, COLLISION (some sphere below
// its plain clearance: returned at the first one), NEAR (none, but some below a margin; out[n]
// and tau[n] per configuration, rows_near per constraint row) or CLEAR. The same tests in the
// same order, the same memory of the last collision (move to front), so the same answers.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "collision.hpp"

namespace dmh {

constexpr int CLEAR = 0, NEAR = 1, COLLISION = 2;
constexpr int64_t GROUP_LANES = 4;  // near lanes from which a link's groups are tested over all lanes

// What check_states writes into, for at most L configurations per call (states.py
// state_workspace): allocated once per plan, it remembers where the last collision was.
struct StateWorkspace {
    int64_t L = 0, nq = 0;
    Buffer q, R, p, Gc, cc, uc, gap, tau_l;
    std::vector<char> keep, hit;
    std::vector<double> pbuf;
    std::vector<int64_t> order, k_first;
    std::vector<char> rows_near;  // (G + P,): a row found below its margin; the caller clears it

    void allocate(const Packed& s, int64_t nq_, int64_t lanes) {
        nq = nq_;
        L = std::max<int64_t>(W, (lanes + W - 1) / W * W);
        q.resize(std::max<int64_t>(nq, 1) * L);
        R.resize(std::max<int64_t>(s.chain.F, 1) * 9 * L);
        p.resize(std::max<int64_t>(s.chain.F, 1) * 3 * L);
        Gc.resize(3 * std::max<int64_t>(s.G, 1) * L);
        cc.resize(3 * L), uc.resize(3 * L), gap.resize(L), tau_l.resize(L);
        keep.assign(L, 0), hit.assign(L, 0);
        pbuf.assign(4 * std::max<int64_t>(s.S, 1), 0.0);
        rows_near.assign(s.G + s.P, 0);
        forget(s);
    }
    // order = 0 .. G-1, no link remembers an obstacle (a fresh workspace's memory)
    void forget(const Packed& s) {
        order.resize(s.G), k_first.assign(s.G, 0);
        for (int64_t g = 0; g < s.G; ++g) order[g] = g;
    }
};

// Spheres s0 .. s1-1 (frame a) of lane b against obstacle k (states.py _spheres_state): CLEAR,
// NEAR (low: the smallest clearance of those below margin) or COLLISION (returned at once).
inline int spheres_state(const Packed& s, int64_t b, int64_t a, int64_t s0, int64_t s1, double margin,
                         double plain, const double* R, const double* p, int64_t L, int64_t k, double& low) {
    int answer = CLEAR;
    low = INF;
    for (int64_t i = s0; i < s1; ++i) {
        double x, y, z;
        lane_point(a, s.s_offset + 3 * i, R, p, L, b, x, y, z);
        if (!point_free(s, k, margin + s.s_radius[i], x, y, z)) {
            if (!point_free(s, k, plain + s.s_radius[i], x, y, z)) return COLLISION;
            answer = NEAR;
            low = smin(low, point_distance(s, k, x, y, z) - s.s_radius[i]);
        }
    }
    return answer;
}

// spheres_state of the groups u0 .. u1-1, a group whose bounding sphere keeps the margin passed
// whole (states.py _groups_state).
__attribute__((noinline)) inline int groups_state(const Packed& s, int64_t b, int64_t a, int64_t u0, int64_t u1,
                                                  double margin, double plain, const double* R, const double* p,
                                                  int64_t L, int64_t k, double& low) {
    int answer = CLEAR;
    low = INF;
    for (int64_t u = u0; u < u1; ++u) {
        double x, y, z;
        lane_point(a, s.u_offset + 3 * u, R, p, L, b, x, y, z);
        if (point_free(s, k, margin + s.u_radius[u], x, y, z)) continue;
        double value;
        const int state = spheres_state(s, b, a, s.u_start[u], s.u_start[u + 1], margin, plain, R, p, L, k, value);
        if (state == COLLISION) return COLLISION;
        if (state == NEAR) answer = NEAR, low = smin(low, value);
    }
    return answer;
}

// How far (in the motion's parameter) link g, gap [m] above its plain clearance in lane b,
// certifies the motion around that state (states.py _link_tau: the static bound gap / Λ_g or the
// local one from the joint axes and the motion's speeds, the larger).
inline double link_tau(const Packed& s, const StateWorkspace& ws, double gap, double inv_lam, int64_t g, int64_t b,
                       int64_t anchor, const double* speeds) {
    const double stat = gap * inv_lam;
    if (inv_lam <= 0.0 || gap <= 0.0) return stat;
    const int64_t L = ws.L;
    const double *R = ws.R.ptr, *p = ws.p.ptr, *Gc = ws.Gc.ptr;
    const double cx = Gc[g * L + b], cy = Gc[(s.G + g) * L + b], cz = Gc[(2 * s.G + g) * L + b];
    const double r = s.g_radius[g];
    double lin = 0.0, Wsum = 0.0;
    for (int64_t k = anchor; k >= 0; k = s.chain.parent[k]) {
        const double wk = speeds[s.chain.qidx[k]];
        if (!(wk > 0.0)) continue;
        if (s.chain.kind[k] == 0) {
            const double ux = cx - p[(k * 3) * L + b], uy = cy - p[(k * 3 + 1) * L + b],
                         uz = cz - p[(k * 3 + 2) * L + b];
            const double ax = R[(k * 9 + 2) * L + b], ay = R[(k * 9 + 5) * L + b], az = R[(k * 9 + 8) * L + b];
            const double X = uy * az - uz * ay, Y = uz * ax - ux * az, Z = ux * ay - uy * ax;
            lin += wk * (std::sqrt(X * X + Y * Y + Z * Z) + r);
            Wsum += wk;
        } else {
            lin += wk;
        }
    }
    if (lin <= 0.0) return stat;
    const double quad = Wsum * (1.0 / inv_lam + Wsum * r);
    return std::max(stat, 2.0 * gap / (lin + std::sqrt(lin * lin + 4.0 * quad * gap)));
}

// The groups u0 .. u1-1 of frame a over all lanes at once, their spheres tested in the lanes
// with hit set (states.py _groups_lanes): COLLISION, NEAR (keep / gap lowered) or CLEAR.
inline int groups_lanes(const Packed& s, StateWorkspace& ws, int64_t m, int64_t a, int64_t u0, int64_t u1,
                        double margin, double plain, int64_t k) {
    const int64_t L = ws.L, nv = (m + W - 1) / W;
    const double *R = ws.R.ptr, *p = ws.p.ptr;
    double *ux = ws.uc.ptr, *uy = ux + L, *uz = uy + L, *gap = ws.gap.ptr;
    int answer = CLEAR;
    for (int64_t u = u0; u < u1; ++u) {
        centres_v(a, s.u_offset + 3 * u, R, p, L, nv, ux, uy, uz);
        for (int64_t v = 0; v < nv; ++v) {
            vi lanes;
            for (int i = 0; i < W; ++i) lanes[i] = ws.hit[v * W + i] ? -1 : 0;
            if (!any(lanes)) continue;
            const vi near = lanes & ~obstacle_free_v(s, k, margin + s.u_radius[u], load(ux + v * W),
                                                     load(uy + v * W), load(uz + v * W), lanes);
            if (!any(near)) continue;
            for (int i = 0; i < W; ++i) {
                if (!near[i]) continue;
                const int64_t b = v * W + i;
                double value;
                const int state = spheres_state(s, b, a, s.u_start[u], s.u_start[u + 1], margin, plain, R, p, L,
                                                k, value);
                if (state == COLLISION) return COLLISION;
                if (state == NEAR) ws.keep[b] = 0, gap[b] = smin(gap[b], value - plain), answer = NEAR;
            }
        }
    }
    return answer;
}

// A collision of link order[gi] with obstacle k: that link first from now on, first against k.
inline void remember(StateWorkspace& ws, int64_t gi, int64_t k) {
    const int64_t g = ws.order[gi];
    ws.k_first[g] = k;
    for (int64_t j = gi; j > 0; --j) ws.order[j] = ws.order[j - 1];
    ws.order[0] = g;
}

// Configurations QT[:, n0:n0+m] (QT (nq, ld) row-major, m <= ws.L) at two clearance levels
// (states.py check_states; its docstring states the contract): COLLISION, NEAR or CLEAR;
// unless COLLISION, out[n0 + b] (kept every margin) and tau[n0 + b] are written. Not inlined:
// its callers compile without fused multiply-adds (motion.hpp), it with them (as numba's).
__attribute__((noinline)) inline int check_states(const Packed& s, const double* QT, int64_t ld, int64_t n0, int64_t m,
                        const double* link_margin, const double* pair_margin, const double* link_plain,
                        const double* pair_plain, const double* inv_lam, const double* speeds, StateWorkspace& ws,
                        bool* out, double* tau) {
    const int64_t L = ws.L, G = s.G, K = s.K, nv = (m + W - 1) / W;
    double *q = ws.q.ptr, *R = ws.R.ptr, *p = ws.p.ptr, *Gc = ws.Gc.ptr;
    double *cx = ws.cc.ptr, *cy = cx + L, *cz = cy + L, *gap = ws.gap.ptr, *tau_l = ws.tau_l.ptr;
    for (int64_t j = 0; j < ws.nq; ++j) {  // transposed into lanes, lanes past m zero
        double* row = q + j * L;
        const double* src = QT + j * ld + n0;
        for (int64_t b = 0; b < m; ++b) row[b] = src[b];
        for (int64_t b = m; b < nv * W; ++b) row[b] = 0.0;
    }
    frames_block(s.chain, q, L, nv, R, p);
    std::vector<vi> in_m_store;  // (small: at most L / W vectors)
    vi in_m[64];
    vi* inm = in_m;
    if (nv > 64) in_m_store.resize(nv), inm = in_m_store.data();
    for (int64_t v = 0; v < nv; ++v)
        for (int i = 0; i < W; ++i) inm[v][i] = v * W + i < m ? -1 : 0;
    for (int64_t b = 0; b < m; ++b) ws.keep[b] = 1, tau_l[b] = INF;
    for (int64_t b = m; b < nv * W; ++b) ws.hit[b] = 0;
    for (int64_t gi = 0; gi < G; ++gi) {
        const int64_t g = ws.order[gi];
        const int64_t k0 = ws.k_first[g] < K ? ws.k_first[g] : 0;
        const int64_t a = s.g_anchor[g];
        const double margin = link_margin[g], plain = link_plain[g];
        double *gx = Gc + g * L, *gy = Gc + (G + g) * L, *gz = Gc + (2 * G + g) * L;
        centres_v(a, s.g_offset + 3 * g, R, p, L, nv, gx, gy, gz);
        for (int64_t b = 0; b < m; ++b) gap[b] = INF;
        bool near_link = false;
        const bool grouped = s.g_ustart[g + 1] - s.g_ustart[g] > 1;
        for (int64_t ki = 0; ki < K; ++ki) {
            const int64_t k = ki == 0 ? k0 : (ki <= k0 ? ki - 1 : ki);
            if (s.o_gap[g * K + k] >= margin) continue;  // no configuration brings them near
            if (!bounding_close(s, g, k, margin, gx, gy, gz, nv, inm)) continue;  // bounding spheres apart
            int64_t c = 0;
            for (int64_t v = 0; v < nv; ++v) {  // the link's bounding sphere vs the obstacle's shape
                const vi h = inm[v] & ~obstacle_free_v(s, k, margin + s.g_radius[g], load(gx + v * W),
                                                       load(gy + v * W), load(gz + v * W), inm[v]);
                for (int i = 0; i < W; ++i) ws.hit[v * W + i] = h[i] != 0, c += h[i] != 0;
            }
            if (c == 0) continue;
            if (c >= GROUP_LANES && grouped) {  // many: each group over all lanes at once
                const int state = groups_lanes(s, ws, m, a, s.g_ustart[g], s.g_ustart[g + 1], margin, plain, k);
                if (state == COLLISION) {
                    remember(ws, gi, k);
                    return COLLISION;
                }
                if (state == NEAR) ws.rows_near[g] = 1, near_link = true;
                continue;
            }
            for (int64_t b = 0; b < m; ++b) {
                if (!ws.hit[b]) continue;
                double value;
                const int state = grouped ? groups_state(s, b, a, s.g_ustart[g], s.g_ustart[g + 1], margin, plain, R,
                                                         p, L, k, value)
                                          : spheres_state(s, b, a, s.g_start[g], s.g_start[g + 1], margin, plain, R,
                                                          p, L, k, value);
                if (state == COLLISION) {
                    remember(ws, gi, k);
                    return COLLISION;
                }
                if (state == NEAR) {
                    ws.keep[b] = 0, ws.rows_near[g] = 1, near_link = true;
                    gap[b] = smin(gap[b], value - plain);
                }
            }
        }
        if (near_link)  // each near lane's tau from its smallest gap to the link's plain clearance
            for (int64_t b = 0; b < m; ++b)
                if (gap[b] < INF) tau_l[b] = smin(tau_l[b], link_tau(s, ws, gap[b], inv_lam[g], g, b, a, speeds));
    }
    for (int64_t i = 0; i < s.P; ++i) {
        if (pair_margin[i] == -INF) continue;  // the caller has certified the pair on these configurations
        const int64_t ga = s.pair_a[i], gb = s.pair_b[i];
        double lim = pair_margin[i] + s.g_radius[ga] + s.g_radius[gb];
        lim *= lim;
        const double *ax = Gc + ga * L, *ay = Gc + (G + ga) * L, *az = Gc + (2 * G + ga) * L;
        const double *bx = Gc + gb * L, *by = Gc + (G + gb) * L, *bz = Gc + (2 * G + gb) * L;
        for (int64_t v = 0; v < nv; ++v) {
            const int64_t o = v * W;
            const vd dx = load(ax + o) - load(bx + o), dy = load(ay + o) - load(by + o),
                     dz = load(az + o) - load(bz + o);
            const vi near = inm[v] & (dx * dx + dy * dy + dz * dz < lim);
            if (!any(near)) continue;
            for (int j = 0; j < W; ++j) {
                if (!near[j]) continue;
                const int64_t b = o + j;
                if (pair_floor(s, i, q + b, L) >= pair_margin[i]) continue;  // the pair's table
                if (capsule_gap(s, b, ga, gb, R, p, L) >= pair_margin[i]) continue;  // the bounding capsules
                const double value = pair_clearance(s, b, ga, gb, pair_margin[i], pair_plain[i], false, ax[b], ay[b],
                                                    az[b], bx[b], by[b], bz[b], R, p, L, ws.pbuf.data());
                if (value < pair_plain[i]) return COLLISION;
                if (value < pair_margin[i]) {
                    ws.keep[b] = 0, ws.rows_near[G + i] = 1;
                    tau_l[b] = smin(tau_l[b], (value - pair_plain[i]) * inv_lam[G + i]);
                }
            }
        }
    }
    int answer = CLEAR;
    for (int64_t b = 0; b < m; ++b) {
        out[n0 + b] = ws.keep[b] != 0;
        tau[n0 + b] = tau_l[b];
        if (!ws.keep[b]) answer = NEAR;
    }
    return answer;
}

// Columns 0 .. n-1 of QT (nq, ld) in blocks (states.py check_blocks): the first of lanes0
// columns, the others of lanes1. Returns COLLISION (stops there), NEAR or CLEAR; used: the
// configurations checked.
inline int check_blocks(const Packed& s, const double* QT, int64_t ld, int64_t n, int64_t lanes0, int64_t lanes1,
                        const double* link_margin, const double* pair_margin, const double* link_plain,
                        const double* pair_plain, const double* inv_lam, const double* speeds, StateWorkspace& ws,
                        bool* out, double* tau, int64_t& used) {
    int answer = CLEAR;
    for (int64_t n0 = 0; n0 < n;) {
        const int64_t m = std::min(n0 == 0 ? lanes0 : lanes1, n - n0);
        const int r = check_states(s, QT, ld, n0, m, link_margin, pair_margin, link_plain, pair_plain, inv_lam,
                                   speeds, ws, out, tau);
        if (r == COLLISION) {
            used = n0 + m;
            return COLLISION;
        }
        if (r == NEAR) answer = NEAR;
        n0 += m;
    }
    used = n;
    return answer;
}

}  // namespace dmh
