// Golden-section refinement of sampled limit ratios of a timed path: the search of
// drake_mh/trajectories/certify.py _refine, one candidate peak at a time, with the trajectory's
// derivatives (ppoly.hpp) and the chain's inverse dynamics (dynamics.hpp) evaluated in place.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdint>
#include <vector>

#include "dynamics.hpp"
#include "ppoly.hpp"

namespace dmh {

// The inverse dynamics of drake_mh.trajectories.dynamics.BatchDynamics (RNEA plus the joints'
// damping and reflected rotor inertia), its arrays borrowed.
struct ChainDynamics {
    int64_t F = 0;
    const int64_t *parent = nullptr, *kind = nullptr, *qidx = nullptr;
    const double *KR = nullptr, *Kp = nullptr, *mass = nullptr, *com = nullptr, *inertia = nullptr,
                 *a_world = nullptr, *damping = nullptr, *reflected = nullptr;

    // tau (N, nq) of Q, V, A (N, nq) row-major
    void torques(const double* Q, const double* V, const double* A, int64_t N, int64_t nq, double* tau) const {
        rnea(F, parent, KR, Kp, kind, qidx, mass, com, inertia, a_world, Q, V, A, N, nq, tau);
        for (int64_t n = 0; n < N; ++n)
            for (int64_t j = 0; j < nq; ++j)
                tau[n * nq + j] += damping[j] * V[n * nq + j] + reflected[j] * A[n * nq + j];
    }
};

// Quantity codes of a candidate: 0 position, 1 velocity, 2 acceleration, 3 jerk (the derivative
// of that order), 4 torque.
constexpr int64_t TORQUE = 4;

// For each of the C candidates (quantity kind[i], joint joint[i], bracket [a[i], b[i]], ratio
// |x - centre[i]| / half[i]) the golden-section search of `iterations` steps for the ratio's
// maximum; out (4, C): the last two probes and their ratios (c, f(c), d, f(d)). The searches run
// in lockstep, each step's probes evaluated in one batch (the torques W at a time); each search
// is the one it would be alone.
inline void golden_refine(const PPoly& path, const PPoly& timing, const ChainDynamics* dynamics,
                          const int64_t* kind, const int64_t* joint, const double* a0, const double* b0,
                          const double* centre, const double* half, int64_t C, int64_t iterations, double* out) {
    const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
    const int64_t nq = path.d;
    int order = 0;
    std::vector<int64_t> torque_rows;  // the candidates asking for torque
    for (int64_t i = 0; i < C; ++i) {
        order = std::max(order, kind[i] == TORQUE ? 2 : (int)kind[i]);
        if (kind[i] == TORQUE) torque_rows.push_back(i);
    }
    const int64_t Ct = (int64_t)torque_rows.size();
    std::vector<double> D((size_t)((order + 1) * C * nq)), Qt((size_t)(3 * Ct * nq)), tau((size_t)(Ct * nq));
    auto ratios = [&](const double* t, double* f) {  // f[i]: candidate i's ratio at t[i]
        timed_derivatives(path, timing, t, C, order, D.data());  // (order + 1, C, nq)
        for (int64_t r = 0; r < Ct; ++r)
            for (int64_t e = 0; e < 3; ++e)
                std::copy_n(&D[(e * C + torque_rows[r]) * nq], nq, &Qt[(e * Ct + r) * nq]);
        if (Ct) dynamics->torques(Qt.data(), Qt.data() + Ct * nq, Qt.data() + 2 * Ct * nq, Ct, nq, tau.data());
        for (int64_t i = 0, r = 0; i < C; ++i) {
            const double x = kind[i] == TORQUE ? tau[(r++) * nq + joint[i]] : D[(kind[i] * C + i) * nq + joint[i]];
            f[i] = std::fabs(x - centre[i]) / half[i];
        }
    };
    std::vector<double> a(a0, a0 + C), b(b0, b0 + C), c(C), d(C), fc(C), fd(C), probe(C), fp(C);
    std::vector<char> left(C);
    for (int64_t i = 0; i < C; ++i) c[i] = b[i] - golden * (b[i] - a[i]), d[i] = a[i] + golden * (b[i] - a[i]);
    ratios(c.data(), fc.data());
    ratios(d.data(), fd.data());
    for (int64_t it = 0; it < iterations; ++it) {
        for (int64_t i = 0; i < C; ++i) {
            left[i] = fc[i] >= fd[i];
            if (left[i]) {  // the maximum in [a, d]
                b[i] = d[i], d[i] = c[i], fd[i] = fc[i];
                probe[i] = c[i] = b[i] - golden * (b[i] - a[i]);
            } else {
                a[i] = c[i], c[i] = d[i], fc[i] = fd[i];
                probe[i] = d[i] = a[i] + golden * (b[i] - a[i]);
            }
        }
        ratios(probe.data(), fp.data());
        for (int64_t i = 0; i < C; ++i) (left[i] ? fc[i] : fd[i]) = fp[i];
    }
    for (int64_t i = 0; i < C; ++i) out[i] = c[i], out[C + i] = fc[i], out[2 * C + i] = d[i], out[3 * C + i] = fd[i];
}

}  // namespace dmh

namespace dmh {

// The sampling and refinement of drake_mh/trajectories/certify.py certify for nQ quantities
// (kinds[iq] as golden_refine's kind; ratio |x - centre[iq, j]| / half[iq, j]):
// samples T (P, K) at fractions tau (K,) of every piece between breaks (P + 1,), pulled inside by
// 1e-9 of the piece (one-sided); D (order + 1, P K, nq) the derivatives there (written);
// worst, when (nQ, nq): per joint the largest ratio sampled and refined, and its time.
// Refinement: sampled local maxima >= threshold ranked per joint by the vertex of the parabola
// through the sample and its neighbours, the per_joint highest searched (golden section,
// `iterations` steps) between their neighbouring samples.
inline void certify_samples(const PPoly& path, const PPoly& timing, const ChainDynamics* dynamics,
                            const double* breaks, int64_t P, const double* tau, int64_t K, const int64_t* kinds,
                            const double* centre, const double* half, int64_t nQ, int order, double threshold,
                            int64_t per_joint, int64_t iterations, double* D, double* worst, double* when) {
    const int64_t nq = path.d, M = P * K;
    std::vector<double> T((size_t)M), lo((size_t)P), hi((size_t)P);
    for (int64_t p = 0; p < P; ++p) {
        const double h = breaks[p + 1] - breaks[p], eps = 1e-9 * h;
        lo[p] = breaks[p] + eps, hi[p] = breaks[p + 1] - eps;
        for (int64_t k = 0; k < K; ++k) T[p * K + k] = std::min(std::max(breaks[p] + tau[k] * h, lo[p]), hi[p]);
    }
    timed_derivatives(path, timing, T.data(), M, order, D);
    std::vector<double> torque;
    for (int64_t iq = 0; iq < nQ; ++iq)
        if (kinds[iq] == TORQUE && torque.empty()) {
            torque.resize((size_t)(M * nq));
            dynamics->torques(D, D + M * nq, D + 2 * M * nq, M, nq, torque.data());
        }
    std::vector<double> r((size_t)(M * nq)), estimate;
    std::vector<int64_t> kind_c, joint_c, order_c;
    std::vector<double> a_c, b_c, centre_c, half_c;
    std::vector<int64_t> owner;  // the quantity of each candidate
    const double minus_inf = -std::numeric_limits<double>::infinity();
    for (int64_t iq = 0; iq < nQ; ++iq) {
        const double* X = kinds[iq] == TORQUE ? torque.data() : D + kinds[iq] * M * nq;
        const double *c_q = centre + iq * nq, *h_q = half + iq * nq;
        for (int64_t n = 0; n < M; ++n)
            for (int64_t j = 0; j < nq; ++j) r[n * nq + j] = std::fabs(X[n * nq + j] - c_q[j]) / h_q[j];
        for (int64_t j = 0; j < nq; ++j) {
            int64_t best = 0;
            for (int64_t n = 1; n < M; ++n)
                if (r[n * nq + j] > r[best * nq + j]) best = n;
            worst[iq * nq + j] = r[best * nq + j], when[iq * nq + j] = T[best];
            // candidate peaks of joint j in sample order, then the per_joint best estimates
            std::vector<int64_t> peaks;
            estimate.clear();
            for (int64_t p = 0; p < P; ++p)
                for (int64_t k = 0; k < K; ++k) {
                    const int64_t n = p * K + k;
                    const double r1 = r[n * nq + j];
                    const double r0 = k > 0 ? r[(n - 1) * nq + j] : minus_inf;
                    const double r2 = k < K - 1 ? r[(n + 1) * nq + j] : minus_inf;
                    if (!(r1 >= r0 && r1 >= r2 && r1 >= threshold && std::isfinite(r1))) continue;
                    const double curvature = r0 - 2.0 * r1 + r2;
                    const bool vertex = std::isfinite(r0) && std::isfinite(r2) && curvature < 0;
                    peaks.push_back(n);
                    estimate.push_back(vertex ? r1 - (r2 - r0) * (r2 - r0) / (8.0 * curvature) : r1);
                }
            std::vector<int64_t> rank(peaks.size());
            for (size_t i = 0; i < rank.size(); ++i) rank[i] = (int64_t)i;
            std::stable_sort(rank.begin(), rank.end(), [&](int64_t x, int64_t y) { return estimate[x] > estimate[y]; });
            for (size_t i = 0; i < rank.size() && (int64_t)i < per_joint; ++i) {
                const int64_t n = peaks[rank[i]], p = n / K, k = n % K;
                kind_c.push_back(kinds[iq]), joint_c.push_back(j), owner.push_back(iq);
                a_c.push_back(k > 0 ? T[n - 1] : lo[p]), b_c.push_back(k < K - 1 ? T[n + 1] : hi[p]);
                centre_c.push_back(c_q[j]), half_c.push_back(h_q[j]);
            }
        }
    }
    const int64_t C = (int64_t)kind_c.size();
    if (C == 0) return;
    std::vector<double> out((size_t)(4 * C));
    golden_refine(path, timing, dynamics, kind_c.data(), joint_c.data(), a_c.data(), b_c.data(), centre_c.data(),
                  half_c.data(), C, iterations, out.data());
    for (int side = 0; side < 2; ++side)  // the c probes, then the d probes (certify's order)
        for (int64_t i = 0; i < C; ++i) {
            const double t = out[2 * side * C + i], f = out[(2 * side + 1) * C + i];
            double& w = worst[owner[i] * nq + joint_c[i]];
            if (f > w) w = f, when[owner[i] * nq + joint_c[i]] = t;
        }
}

// The Bernstein bounds of drake_mh/trajectories/bound.py kinematic_bound from certify_samples'
// samples D (order + 1, P K, nq): for each quantity iq with n1[iq] > 0 nodes, the values V
// (P, n1, nq) of D[kinds[iq]] at the samples picks (n1,) of every piece, their coefficients
// B = M0 V, and the halving loop (bernstein_bound, from the ratios in worst); worst[iq] becomes
// the larger. mats: per such quantity M0, left, right (n1, n1) each, in order.
inline void sample_bounds(const double* D, int64_t P, int64_t K, int64_t nq, const int64_t* kinds, int64_t nQ,
                          const int64_t* n1s, const int64_t* picks, const double* mats, const double* centre,
                          const double* half, double slack, int64_t max_levels, double* worst) {
    const int64_t M = P * K;
    std::vector<double> V, B, certified((size_t)nq);
    for (int64_t iq = 0; iq < nQ; ++iq) {
        const int64_t n1 = n1s[iq];
        if (n1 <= 0) continue;
        const double *M0 = mats, *left = M0 + n1 * n1, *right = left + n1 * n1;
        const double* X = D + kinds[iq] * M * nq;
        V.resize((size_t)(P * n1 * nq)), B.assign((size_t)(P * n1 * nq), 0.0);
        for (int64_t p = 0; p < P; ++p)
            for (int64_t i = 0; i < n1; ++i) std::copy_n(&X[(p * K + picks[i]) * nq], nq, &V[(p * n1 + i) * nq]);
        for (int64_t p = 0; p < P; ++p)
            for (int64_t a = 0; a < n1; ++a) {
                double* Ba = &B[(p * n1 + a) * nq];
                for (int64_t b = 0; b < n1; ++b) {
                    const double w = M0[a * n1 + b], *Vb = &V[(p * n1 + b) * nq];
                    for (int64_t j = 0; j < nq; ++j) Ba[j] += w * Vb[j];
                }
            }
        double* w = worst + iq * nq;
        bernstein_bound(B.data(), P, n1, nq, V.data(), P, n1, centre + iq * nq, half + iq * nq, w, slack, max_levels,
                        left, right, certified.data());
        for (int64_t j = 0; j < nq; ++j) w[j] = std::max(w[j], certified[j]);
        picks += n1, mats += 3 * n1 * n1;
    }
}

}  // namespace dmh
