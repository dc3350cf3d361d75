// Certified straight joint-space segments: drake_mh/scene/kernels/segments.py certify_segments,
// the same bisection on the same values (clearances.hpp), so the same verdicts up to round-off for
// a segment certified alone (many in one call share batches: see certify_segments below).
//
// Per segment q(t) = qa + t (qb - qa), every value V_c of the per-link evaluation is Lipschitz in
// t with constant lam_c = sum_j reach[c, j] |dq_j| (plus the obstacles' largest displacement for
// link rows); a piece [t0, t1] of length h is certified where min(V0, V1, (V0 + V1 - lam h) / 2)
// keeps the clearance, else it is cut in two (all pieces of a level evaluated in one batch) until
// every piece is certified, a configuration below the clearance is found (BLOCKED), or a piece is
// shorter than min_piece or the budget is spent (UNDECIDED). A link row's piece also has the
// curvature bound of segments.py (curved_bound) where no obstacle is a convex mesh piece.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "clearances.hpp"
#include "pieces.hpp"

namespace dmh {

constexpr int64_t CERTIFIED = 1, BLOCKED = 0, UNDECIDED = -1;

inline double piece_bound(double V0, double V1, double lam, double h) {
    return smin(smin(V0, V1), 0.5 * (V0 + V1 - lam * h));
}

// A link row's bound on a piece from the curvature of its value (segments.py _curved_bound): each
// sphere-obstacle value d(x(t)) - r is at least the Lipschitz bound L on the piece, so the
// distance d of the sphere's centre to the convex obstacle (or cloud point) is at least
// L + rmin there, and d(x(t))'' <= |x'|^2 / d + |x''| <= lam^2 / (L + rmin) + acc = K; the row
// (their minimum) then keeps V >= chord - K (t - t0)(t1 - t) / 2 on the piece. The larger of
// that minimum and L.
inline double curved_bound(double V0, double V1, double lam, double acc, double rmin, double h) {
    const double L = piece_bound(V0, V1, lam, h);
    const double delta = L + rmin;
    if (!(delta > 0.0) || !(std::fabs(V0) < INF) || !(std::fabs(V1) < INF)) return L;
    const double a = 0.5 * (lam * lam / delta + acc) * h * h;
    const double D = V1 - V0;
    if (!(a > 0.0)) return smax(L, smin(V0, V1));
    const double u = smin(smax((a - D) / (2.0 * a), 0.0), 1.0);
    return smax(L, V0 + D * u - a * u * (1.0 - u));
}

// The verdicts on the M segments QA[i] -> QB[i] (M, nq) row-major: reach (C, nq) with C = G + P;
// v_WO (K, 3) the obstacles' displacement over a whole segment, speed its largest norm; outputs
// (M,) status, t_stop, lower, lower_self, evals as segments.py certify_segments.
//
// Every segment runs the bisection above on its own pieces, in the same order; the segments go
// level by level together, so that each level's new configurations (and first the ends) of all
// segments are evaluated in one batch (a batch of one or two configurations costs nearly as much
// as a full block of lanes). With standing obstacles, a segment that starts where the one before
// ended (a path) reads that end's values instead of evaluating it again, where its link pairs are
// evaluated alike (the same pairs tabled); it counts among the segment's evaluations as before.
inline void certify_segments(Clearances& cl, const double* QA, const double* QB, int64_t M, const double* reach,
                             const double* v_WO, double speed, double clearance, double self_clearance,
                             double tolerance, double min_piece, int64_t max_evals, int64_t* status, double* t_stop,
                             double* lower, double* lower_self, int64_t* evals) {
    const Packed& s = cl.packed();
    const int64_t G = s.G, P = s.P, C = G + P, nq = cl.nq();
    const double NaN = std::nan("");
    // fine spheres below 5 cm above the requirement (bounding spheres above it); for the links
    // everywhere when a tight bound is asked for (segments.py)
    const double fine = tolerance == INF ? smin(clearance, self_clearance) + 0.05 : INF;
    const double pair_fine = tolerance == INF ? smin(clearance, self_clearance) + 0.05 : self_clearance + 0.05;
    bool standing = true;
    for (int64_t k = 0; k < 3 * s.K; ++k) standing &= v_WO[k] == 0.0;
    // the curvature bound of the link rows: every obstacle's distance smooth and convex outside it
    // (not a convex mesh piece's, the largest of its planes' distances); per link its smallest sphere
    bool curved = true;
    for (int64_t k = 0; k < s.K; ++k) curved &= s.kinds[k] != CONVEX;
    std::vector<double> rmin(G, INF), acc(M * G, 0.0);
    for (int64_t g = 0; g < G; ++g)
        for (int64_t k = s.g_start[g]; k < s.g_start[g + 1]; ++k) rmin[g] = smin(rmin[g], s.s_radius[k]);
    // per segment: its Lipschitz constants, pair floors and fines (M, C) / (M, P) / (M, P), the
    // parameters and values it evaluated (ts[i], vals[i] (n, C)), its open pieces, its bounds
    std::vector<double> lam(M * C), floors(M * P), fines(M * P), low(M, INF), low_self(M, INF);
    std::vector<char> tabled(M * P);
    std::vector<double> tabled_low(M, INF);  // per segment the smallest floor of its tabled pairs
    std::vector<std::vector<int64_t>> open_pairs(M);  // per segment the rows (G + r) of its other pairs
    std::vector<std::vector<double>> ts(M), vals(M);
    std::vector<std::vector<int64_t>> pieces(M);
    for (int64_t i = 0; i < M; ++i) {
        const double *qa = QA + i * nq, *qb = QB + i * nq;
        for (int64_t r = 0; r < P; ++r) {  // pairs whose floor table keeps them clear along the whole segment
            floors[i * P + r] = s.t_meta[6 * r] != 0 ? segment_floor(s, r, qa, qb) : -INF;
            tabled[i * P + r] = floors[i * P + r] >= self_clearance;
            fines[i * P + r] = tabled[i * P + r] ? -INF : pair_fine;
            if (tabled[i * P + r])
                tabled_low[i] = smin(tabled_low[i], floors[i * P + r]);
            else
                open_pairs[i].push_back(G + r);
        }
        for (int64_t c = 0; c < C; ++c) {
            double sum = 0.0;
            for (int64_t j = 0; j < nq; ++j) sum += reach[c * nq + j] * std::fabs(qb[j] - qa[j]);
            lam[i * C + c] = sum + (c < G ? speed : 0.0);
        }
        for (int64_t c = 0; curved && c < G; ++c) {  // |x''| <= sum_jk |dq_j| |dq_k| max(reach_j, reach_k)
            const double* rc = reach + c * nq;
            double sum = 0.0;
            for (int64_t j = 0; j < nq; ++j)
                for (int64_t k = 0; k < nq; ++k)
                    sum += std::fabs(qb[j] - qa[j]) * std::fabs(qb[k] - qa[k]) * smax(rc[j], rc[k]);
            acc[i * G + c] = sum;
        }
        status[i] = CERTIFIED, t_stop[i] = NaN;
    }
    auto below = [&](int64_t i, const double* row) {  // a value of the row below its requirement (tabled pairs clear)
        for (int64_t c = 0; c < G; ++c)
            if (row[c] < clearance) return true;
        for (const int64_t c : open_pairs[i])
            if (row[c] < self_clearance) return true;
        return false;
    };
    // one batch: configurations Qb (n, nq) at parameters tb (n,), pair fines fb (n, P); where each
    // value row goes: segment own[b] (its row slot[b])
    std::vector<double> Qb, tb, fb, out;
    std::vector<int64_t> own, slot;
    auto add = [&](int64_t i, int64_t e, double t) {
        const double *qa = QA + i * nq, *qb = QB + i * nq;
        for (int64_t j = 0; j < nq; ++j) Qb.push_back(qa[j] + t * (qb[j] - qa[j]));
        if (t == 0.0) std::copy(qa, qa + nq, Qb.end() - nq);  // the ends exactly
        if (t == 1.0) std::copy(qb, qb + nq, Qb.end() - nq);
        tb.push_back(t), own.push_back(i), slot.push_back(e);
        fb.insert(fb.end(), fines.begin() + i * P, fines.begin() + (i + 1) * P);
    };
    auto run = [&]() {
        const int64_t n = (int64_t)tb.size();
        out.resize(std::max<int64_t>(n * C, 1));
        if (n) cl.evaluate(Qb.data(), n, tb.data(), fine, fb.data(), PER_LINK, v_WO, out.data(), true);
        for (int64_t b = 0; b < n; ++b)
            std::copy(out.begin() + b * C, out.begin() + (b + 1) * C, vals[own[b]].begin() + slot[b] * C);
        Qb.clear(), tb.clear(), fb.clear(), own.clear(), slot.clear();
    };
    // the ends: each segment's start (or the last segment's end, read again) and end
    std::vector<int64_t> reuse(M, 0);
    for (int64_t i = 0; i < M; ++i) {
        ts[i] = {0.0, 1.0};
        vals[i].resize(2 * C);
        reuse[i] = standing && i > 0 && std::equal(QA + i * nq, QA + (i + 1) * nq, QB + (i - 1) * nq) &&
                   std::equal(tabled.begin() + i * P, tabled.begin() + (i + 1) * P, tabled.begin() + (i - 1) * P);
        if (!reuse[i]) add(i, 0, 0.0);
        add(i, 1, 1.0);
    }
    run();
    for (int64_t i = 0; i < M; ++i) {
        if (reuse[i]) std::copy(vals[i - 1].begin() + C, vals[i - 1].begin() + 2 * C, vals[i].begin());
        for (int64_t e = 0; e < 2 && status[i] == CERTIFIED; ++e)
            if (below(i, vals[i].data() + e * C)) status[i] = BLOCKED, t_stop[i] = ts[i][e];
        if (status[i] == CERTIFIED) pieces[i] = {0, 1};
    }
    std::vector<int64_t> fresh, first_new(M);
    bool open = true;
    while (open) {  // one level of every segment still open
        open = false;
        for (int64_t i = 0; i < M; ++i) {
            std::vector<int64_t>& pc = pieces[i];
            first_new[i] = (int64_t)ts[i].size();
            if (status[i] != CERTIFIED || pc.empty()) continue;
            const int64_t R = (int64_t)pc.size() / 2, n = (int64_t)ts[i].size();
            const double* V = vals[i].data();
            const double* lm = lam.data() + i * C;
            fresh.clear();
            int64_t count = 0;
            for (int64_t r = 0; r < R; ++r) {
                const int64_t e0 = pc[2 * r], e1 = pc[2 * r + 1];
                const double h = ts[i][e1] - ts[i][e0];
                bool ok = true;
                double lo = INF, lo_self = tabled_low[i], seen = INF;  // tabled pairs: their floors, >= self_clearance
                for (int64_t c = 0; c < G; ++c) {
                    const double v0 = V[e0 * C + c], v1 = V[e1 * C + c];
                    const double bound = curved ? curved_bound(v0, v1, lm[c], acc[i * G + c], rmin[c], h)
                                                : piece_bound(v0, v1, lm[c], h);
                    ok &= bound >= clearance;
                    lo = smin(lo, bound);
                    seen = smin(seen, smin(v0, v1));
                }
                for (const int64_t c : open_pairs[i]) {
                    const double bound = piece_bound(V[e0 * C + c], V[e1 * C + c], lm[c], h);
                    ok &= bound >= self_clearance;
                    lo_self = smin(lo_self, bound);
                }
                if (ok && !(lo < seen - tolerance)) {
                    low[i] = smin(low[i], lo), low_self[i] = smin(low_self[i], lo_self);
                    continue;
                }
                if (h < min_piece || n + count + 1 > max_evals) {
                    if (ok) {  // certified, only not as tight as asked
                        low[i] = smin(low[i], lo), low_self[i] = smin(low_self[i], lo_self);
                        continue;
                    }
                    status[i] = UNDECIDED, t_stop[i] = ts[i][e0];
                    break;
                }
                fresh.insert(fresh.end(), {e0, n + count, n + count, e1});
                ++count;
            }
            if (status[i] != CERTIFIED || count == 0) {
                pc.clear();
                continue;
            }
            for (int64_t w = 0; w < count; ++w) {  // the midpoints, in the order of the pieces
                const double t = 0.5 * (ts[i][fresh[4 * w]] + ts[i][fresh[4 * w + 3]]);
                ts[i].push_back(t);
                add(i, n + w, t);
            }
            vals[i].resize((n + count) * C);
            pc.swap(fresh);
            open = true;
        }
        if (!open) break;
        run();
        for (int64_t i = 0; i < M; ++i) {  // a new configuration below the requirement blocks its segment
            if (status[i] != CERTIFIED || pieces[i].empty()) continue;
            double first = INF;
            for (int64_t e = first_new[i]; e < (int64_t)ts[i].size(); ++e)
                if (below(i, vals[i].data() + e * C)) first = smin(first, ts[i][e]);
            if (first < INF) status[i] = BLOCKED, t_stop[i] = first, pieces[i].clear();
        }
    }
    for (int64_t i = 0; i < M; ++i) {
        evals[i] = (int64_t)ts[i].size();
        if (status[i] == CERTIFIED)
            lower[i] = low[i], lower_self[i] = low_self[i];
        else
            lower[i] = lower_self[i] = NaN;
    }
}

}  // namespace dmh
