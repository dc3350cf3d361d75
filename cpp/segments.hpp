// Certified straight joint-space segments: drake_mh/scene/kernels/segments.py certify_segments,
// the same bisection on the same values (clearances.hpp), so the same verdicts up to round-off.
//
// Per segment q(t) = qa + t (qb - qa), every value V_c of the per-link evaluation is Lipschitz in
// t with constant lam_c = sum_j reach[c, j] |dq_j| (plus the obstacles' largest displacement for
// link rows); a piece [t0, t1] of length h is certified where min(V0, V1, (V0 + V1 - lam h) / 2)
// keeps the clearance, else it is cut in two (all pieces of a level evaluated in one batch) until
// every piece is certified, a configuration below the clearance is found (BLOCKED), or a piece is
// shorter than min_piece or the budget is spent (UNDECIDED).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "clearances.hpp"

namespace dmh {

constexpr int64_t CERTIFIED = 1, BLOCKED = 0, UNDECIDED = -1;

inline double piece_bound(double V0, double V1, double lam, double h) {
    return smin(smin(V0, V1), 0.5 * (V0 + V1 - lam * h));
}

// The verdicts on the M segments QA[i] -> QB[i] (M, nq) row-major: reach (C, nq) with C = G + P;
// v_WO (K, 3) the obstacles' displacement over a whole segment, speed its largest norm; outputs
// (M,) status, t_stop, lower, lower_self, evals as segments.py certify_segments.
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
    std::vector<double> lam(C), fines(P), floors(P), vals, ts, Q, tau;
    std::vector<char> tabled(P), split;
    std::vector<int64_t> pieces, fresh;
    for (int64_t i = 0; i < M; ++i) {
        const double *qa = QA + i * nq, *qb = QB + i * nq;
        for (int64_t r = 0; r < P; ++r) {  // pairs whose floor table keeps them clear along the whole segment
            floors[r] = s.t_meta[6 * r] != 0 ? segment_floor(s, r, qa, qb) : -INF;
            tabled[r] = floors[r] >= self_clearance;
            fines[r] = tabled[r] ? -INF : pair_fine;
        }
        for (int64_t c = 0; c < C; ++c) {
            double acc = 0.0;
            for (int64_t j = 0; j < nq; ++j) acc += reach[c * nq + j] * std::fabs(qb[j] - qa[j]);
            lam[c] = acc + (c < G ? speed : 0.0);
        }
        auto below = [&](const double* row, int64_t c) {
            return row[c] < (c < G ? clearance : self_clearance) && !(c >= G && tabled[c - G]);
        };
        vals.resize(64 * C), ts.resize(64);
        Q.assign(qa, qa + nq);
        Q.insert(Q.end(), qb, qb + nq);
        ts[0] = 0.0, ts[1] = 1.0;
        cl.evaluate(Q.data(), 2, ts.data(), fine, fines.data(), PER_LINK, v_WO, vals.data());
        int64_t n = 2;
        status[i] = CERTIFIED, t_stop[i] = NaN;
        double low = INF, low_self = INF;
        for (int64_t e = 0; e < 2 && status[i] == CERTIFIED; ++e)
            for (int64_t c = 0; c < C; ++c)
                if (below(vals.data() + e * C, c)) {
                    status[i] = BLOCKED, t_stop[i] = ts[e];
                    break;
                }
        if (status[i] == BLOCKED) {
            lower[i] = lower_self[i] = NaN, evals[i] = n;
            continue;
        }
        pieces.assign({0, 1});
        while (!pieces.empty() && status[i] == CERTIFIED) {
            const int64_t R = (int64_t)pieces.size() / 2;
            split.assign(R, 0);
            int64_t count = 0;
            for (int64_t r = 0; r < R; ++r) {
                const int64_t e0 = pieces[2 * r], e1 = pieces[2 * r + 1];
                const double h = ts[e1] - ts[e0];
                bool ok = true;
                double lo = INF, lo_self = INF, seen = INF;
                for (int64_t c = 0; c < C; ++c) {
                    const double v0 = vals[e0 * C + c], v1 = vals[e1 * C + c];
                    const double bound = c >= G && tabled[c - G] ? floors[c - G] : piece_bound(v0, v1, lam[c], h);
                    if (c < G) {
                        ok &= bound >= clearance;
                        lo = smin(lo, bound);
                        seen = smin(seen, smin(v0, v1));
                    } else {
                        ok &= bound >= self_clearance;
                        lo_self = smin(lo_self, bound);
                    }
                }
                if (ok && !(lo < seen - tolerance)) {
                    low = smin(low, lo), low_self = smin(low_self, lo_self);
                    continue;
                }
                if (h < min_piece || n + count + 1 > max_evals) {
                    if (ok) {  // certified, only not as tight as asked
                        low = smin(low, lo), low_self = smin(low_self, lo_self);
                        continue;
                    }
                    status[i] = UNDECIDED, t_stop[i] = ts[e0];
                    break;
                }
                split[r] = 1;
                ++count;
            }
            if (status[i] != CERTIFIED || count == 0) break;
            if ((int64_t)ts.size() < n + count) {  // grow the store
                size_t cap = ts.size();
                while ((int64_t)cap < n + count) cap *= 2;
                ts.resize(cap), vals.resize(cap * C);
            }
            Q.resize(count * nq), tau.resize(count), fresh.resize(4 * count);
            int64_t w = 0;
            for (int64_t r = 0; r < R; ++r) {
                if (!split[r]) continue;
                const int64_t e0 = pieces[2 * r], e1 = pieces[2 * r + 1];
                const double t = 0.5 * (ts[e0] + ts[e1]);
                ts[n + w] = tau[w] = t;
                for (int64_t j = 0; j < nq; ++j) Q[w * nq + j] = qa[j] + t * (qb[j] - qa[j]);
                fresh[4 * w] = e0, fresh[4 * w + 1] = n + w, fresh[4 * w + 2] = n + w, fresh[4 * w + 3] = e1;
                ++w;
            }
            cl.evaluate(Q.data(), count, tau.data(), fine, fines.data(), PER_LINK, v_WO, vals.data() + n * C);
            double first = INF;
            for (int64_t e = n; e < n + count; ++e)
                for (int64_t c = 0; c < C; ++c)
                    if (below(vals.data() + e * C, c)) first = smin(first, ts[e]);
            n += count;
            if (first < INF) {
                status[i] = BLOCKED, t_stop[i] = first;
                break;
            }
            pieces.swap(fresh);
        }
        evals[i] = n;
        if (status[i] == CERTIFIED)
            lower[i] = low, lower_self[i] = low_self;
        else
            lower[i] = lower_self[i] = NaN;
    }
}

}  // namespace dmh
