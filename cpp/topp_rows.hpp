// The gridpoints and stage rows of toppra on a joint spline: the answers of
// drake_mh/trajectories/toppra_time.py _gridpoints (toppra's propose_gridpoints, the knots added)
// and drake_mh/trajectories/toppra_solve.py stage_rows(...).canonical(), for topp_ra (topp.hpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ppoly.hpp"
#include "refine.hpp"

namespace dmh {

// toppra's propose_gridpoints on the spline sp (d = nq, breaks from 0): passes that halve every
// interval longer than max_seg or whose interpolation error 0.5 max_j |p_j''(mid)| h^2 exceeds
// max_err, then halvings of every interval until there are min_nb points; then the spline's
// knots added, points closer than 1e-9 of the length to the previous one dropped, the ends
// exactly 0 and the length. False where the passes did not settle within max_iteration (the
// reference's test: its last pass index is max_iteration - 1).
inline bool spline_gridpoints(const PPoly& sp, double max_err, int64_t max_iteration, double max_seg, int64_t min_nb,
                              std::vector<double>& gp) {
    const int64_t nq = sp.d;
    const double s_end = sp.x[sp.m];
    gp.assign({sp.x[0], s_end});
    std::vector<double> p((size_t)(3 * nq)), next;
    int64_t last = max_iteration > 0 ? max_iteration - 1 : 0;  // the reference's pass index when none ran: 0
    for (int64_t iteration = 0; iteration < max_iteration; ++iteration) {
        next.clear();
        bool split_any = false;
        for (size_t i = 0; i + 1 < gp.size(); ++i) {
            next.push_back(gp[i]);
            const double mid = 0.5 * (gp[i] + gp[i + 1]), h = gp[i + 1] - gp[i];
            bool split = h > max_seg;
            if (!split) {
                ppoly_derivatives(sp, sp.piece(mid), mid, 2, p.data());
                const double h2 = h * h;
                for (int64_t j = 0; j < nq; ++j) split |= std::fabs(0.5 * p[2 * nq + j] * h2) > max_err;
            }
            if (split) next.push_back(mid), split_any = true;
        }
        if (!split_any) {
            last = iteration;
            break;
        }
        next.push_back(gp.back());
        gp.swap(next);
    }
    while ((int64_t)gp.size() < min_nb) {
        next.clear();
        for (size_t i = 0; i + 1 < gp.size(); ++i) next.push_back(gp[i]), next.push_back(0.5 * (gp[i] + gp[i + 1]));
        next.push_back(gp.back());
        gp.swap(next);
    }
    gp.insert(gp.end(), sp.x, sp.x + sp.m + 1);
    std::sort(gp.begin(), gp.end());
    gp.erase(std::unique(gp.begin(), gp.end()), gp.end());
    next.assign(1, gp[0]);
    for (size_t i = 1; i < gp.size(); ++i)
        if (gp[i] - gp[i - 1] > 1e-9 * s_end) next.push_back(gp[i]);
    gp.swap(next);
    gp.front() = 0.0, gp.back() = s_end;
    return last != max_iteration - 1;
}

// The rows of stage_rows(...).canonical() (A, B, C (N1, 2 F m) and x_lo, x_hi (N1,)) for the
// gridpoints gp (N1,) at the fractions phi (F,) of every interval: velocity (p'^2 against vmax^2),
// acceleration (p', p'') and torque (a = M p', b = M p'' + C p', c = g by inverse dynamics) rows
// for each quantity with a finite limit; the velocity bound on x at the gridpoints where asked.
struct StageRowsOut {
    std::vector<double> A, B, C, x_lo, x_hi;
    int64_t R = 0;
};

inline void spline_stage_rows(const PPoly& sp, const double* gp, int64_t N1, const double* vmax, const double* amax,
                              const double* tmax, const double* phi, int64_t F, bool velocity_bound,
                              const ChainDynamics* dynamics, StageRowsOut& out) {
    const int64_t nq = sp.d;
    auto finite_any = [&](const double* x) {
        for (int64_t j = 0; j < nq; ++j)
            if (std::isfinite(x[j])) return true;
        return false;
    };
    const bool use_vel = finite_any(vmax), use_acc = finite_any(amax), use_tau = finite_any(tmax) && dynamics;
    std::vector<double> lims;
    for (int64_t j = 0; use_vel && j < nq; ++j) lims.push_back(std::min(vmax[j] * vmax[j], 1e12));
    for (int64_t j = 0; use_acc && j < nq; ++j) lims.push_back(std::min(amax[j], 1e12));
    for (int64_t j = 0; use_tau && j < nq; ++j) lims.push_back(std::min(tmax[j], 1e12));
    const int64_t m = (int64_t)lims.size(), R = 2 * F * m;
    // the check points, each distinct one evaluated once (an interval's end is the next gridpoint)
    std::vector<double> sig((size_t)(N1 * F));
    for (int64_t i = 0; i < N1; ++i) {
        const double h = i + 1 < N1 ? gp[i + 1] - gp[i] : 0.0;
        for (int64_t f = 0; f < F; ++f) {
            double s = gp[i] + phi[f] * h;
            if (phi[f] == 0.0) s = gp[i];
            if (phi[f] == 1.0 && i + 1 < N1) s = gp[i + 1];
            sig[i * F + f] = s;
        }
    }
    std::vector<double> S(sig);
    std::sort(S.begin(), S.end());
    S.erase(std::unique(S.begin(), S.end()), S.end());
    const int64_t M = (int64_t)S.size();
    std::vector<double> P((size_t)(M * nq)), Ps((size_t)(M * nq)), Pss((size_t)(M * nq)), p((size_t)(3 * nq));
    for (int64_t n = 0; n < M; ++n) {
        ppoly_derivatives(sp, sp.piece(S[n]), S[n], 2, p.data());
        std::copy_n(p.data(), nq, &P[n * nq]);
        std::copy_n(p.data() + nq, nq, &Ps[n * nq]);
        std::copy_n(p.data() + 2 * nq, nq, &Pss[n * nq]);
    }
    std::vector<double> ta, tb, tc;  // torque rows per point: a = tau(P, 0, Ps) - g, b = tau(P, Ps, Pss) - g, c = g
    if (use_tau) {
        std::vector<double> Q3((size_t)(3 * M * nq)), V3((size_t)(3 * M * nq), 0.0), A3((size_t)(3 * M * nq), 0.0),
            tau((size_t)(3 * M * nq));
        for (int64_t k = 0; k < 3; ++k) std::copy(P.begin(), P.end(), Q3.begin() + k * M * nq);
        std::copy(Ps.begin(), Ps.end(), A3.begin() + M * nq);
        std::copy(Ps.begin(), Ps.end(), V3.begin() + 2 * M * nq);
        std::copy(Pss.begin(), Pss.end(), A3.begin() + 2 * M * nq);
        dynamics->torques(Q3.data(), V3.data(), A3.data(), 3 * M, nq, tau.data());
        tc.assign(tau.begin(), tau.begin() + M * nq);
        ta.resize((size_t)(M * nq)), tb.resize((size_t)(M * nq));
        for (int64_t e = 0; e < M * nq; ++e) ta[e] = tau[M * nq + e] - tc[e], tb[e] = tau[2 * M * nq + e] - tc[e];
    }
    out.R = R;
    out.A.assign((size_t)(N1 * R), 0.0), out.B.assign((size_t)(N1 * R), 0.0), out.C.assign((size_t)(N1 * R), 0.0);
    std::vector<double> a((size_t)m), b((size_t)m), c((size_t)m);
    for (int64_t i = 0; i < N1; ++i)
        for (int64_t f = 0; f < F; ++f) {
            const double s = sig[i * F + f], off = 2.0 * (s - gp[i]);
            const int64_t n = std::lower_bound(S.begin(), S.end(), s) - S.begin();
            int64_t r = 0;
            for (int64_t j = 0; use_vel && j < nq; ++j, ++r)
                a[r] = 0.0, b[r] = Ps[n * nq + j] * Ps[n * nq + j], c[r] = 0.0;
            for (int64_t j = 0; use_acc && j < nq; ++j, ++r) a[r] = Ps[n * nq + j], b[r] = Pss[n * nq + j], c[r] = 0.0;
            for (int64_t j = 0; use_tau && j < nq; ++j, ++r)
                a[r] = ta[n * nq + j], b[r] = tb[n * nq + j], c[r] = tc[n * nq + j];
            double *Ai = &out.A[i * R + f * 2 * m], *Bi = &out.B[i * R + f * 2 * m], *Ci = &out.C[i * R + f * 2 * m];
            for (int64_t k = 0; k < m; ++k) {
                const double ak = a[k] + off * b[k];
                Ai[k] = ak, Ai[m + k] = -ak;
                Bi[k] = b[k], Bi[m + k] = -b[k];
                Ci[k] = c[k] - lims[k], Ci[m + k] = -c[k] - lims[k];
            }
        }
    out.x_lo.assign((size_t)N1, velocity_bound ? 0.0 : -INFINITY);
    out.x_hi.assign((size_t)N1, INFINITY);
    if (!velocity_bound) return;
    for (int64_t i = 0; i < N1; ++i) {
        ppoly_derivatives(sp, sp.piece(gp[i]), gp[i], 1, p.data());
        double x = INFINITY;
        for (int64_t j = 0; j < nq; ++j) {
            const double ps = std::fabs(p[nq + j]);
            if (ps > 0) x = std::min(x, vmax[j] * vmax[j] / (ps * ps));
        }
        out.x_hi[i] = std::min(x, 1e16);
    }
}

}  // namespace dmh
