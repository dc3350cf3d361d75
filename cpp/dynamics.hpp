// Inverse dynamics of a compiled chain (recursive Newton-Euler) and the Bernstein bound's
// halving loop: the answers of drake_mh/trajectories/dynamics.py _rnea and bound.py _subdivide.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kinematics.hpp"

namespace dmh {

template <class T>
inline void cross3(const T* a, const T* b, T* out) {
    const T x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}

// Work space of rnea_lanes for a chain of F frames and nq coordinates (lane vectors).
struct RneaWork {
    std::vector<vd> R, o, w, dw, acc, force, moment, q, qd, qdd, tau;
    RneaWork(int64_t F, int64_t nq)
        : R(9 * F), o(3 * F), w(3 * F), dw(3 * F), acc(3 * F), force(3 * F), moment(3 * F), q(nq), qd(nq),
          qdd(nq), tau(nq) {}
};

// The RNEA of rnea for W samples at once, one per lane of the vectors in ws.q, ws.qd, ws.qdd
// (nq,); writes ws.tau (nq,). Every lane runs the same operations: a sample's torques do not
// depend on its lane or on the other lanes.
inline void rnea_lanes(int64_t F, const int64_t* parent, const double* KR, const double* Kp, const int64_t* kind,
                       const int64_t* qidx, const double* mass, const double* com, const double* inertia,
                       const double* a_world, RneaWork& ws) {
    const vd one = splat(1.0), nil = splat(0.0);
    const vd eye[9] = {one, nil, nil, nil, one, nil, nil, nil, one}, zero[3] = {nil, nil, nil};
    const vd base[3] = {splat(a_world[0]), splat(a_world[1]), splat(a_world[2])};
    vd r[3], z[3], t1[3], t2[3], c[3], I[9], RI[9];
    vd *R = ws.R.data(), *o = ws.o.data(), *w = ws.w.data(), *dw = ws.dw.data(), *acc = ws.acc.data();
    vd *force = ws.force.data(), *moment = ws.moment.data();
    for (int64_t k = 0; k < F; ++k) {
        const int64_t p = parent[k], i = qidx[k];
        const vd q = ws.q[i], qd = ws.qd[i], qdd = ws.qdd[i];
        const vd* Rp = p < 0 ? eye : &R[9 * p];
        const vd* wp = p < 0 ? zero : &w[3 * p];
        const vd* dwp = p < 0 ? zero : &dw[3 * p];
        const vd* ap = p < 0 ? base : &acc[3 * p];
        const double* K = KR + 9 * k;
        const double* kp = Kp + 3 * k;
        for (int a = 0; a < 3; ++a) r[a] = Rp[3 * a] * kp[0] + Rp[3 * a + 1] * kp[1] + Rp[3 * a + 2] * kp[2];
        vd cq, sq;
        vsincos(q, sq, cq);
        vd* Rk = &R[9 * k];
        for (int a = 0; a < 3; ++a) {
            const vd* Ra = Rp + 3 * a;
            const vd r0 = Ra[0] * K[0] + Ra[1] * K[3] + Ra[2] * K[6];
            const vd r1 = Ra[0] * K[1] + Ra[1] * K[4] + Ra[2] * K[7];
            const vd r2 = Ra[0] * K[2] + Ra[1] * K[5] + Ra[2] * K[8];
            z[a] = r2;
            if (kind[k] == 1) {
                Rk[3 * a] = r0, Rk[3 * a + 1] = r1, Rk[3 * a + 2] = r2;
            } else {
                Rk[3 * a] = r0 * cq + r1 * sq;
                Rk[3 * a + 1] = r1 * cq - r0 * sq;
                Rk[3 * a + 2] = r2;
            }
        }
        if (kind[k] == 1)
            for (int a = 0; a < 3; ++a) r[a] += z[a] * q;
        cross3(dwp, r, t1);  // a_k = a_p + dw_p x r + w_p x (w_p x r)
        cross3(wp, r, c);
        cross3(wp, c, t2);
        for (int a = 0; a < 3; ++a) {
            acc[3 * k + a] = ap[a] + t1[a] + t2[a];
            o[3 * k + a] = (p < 0 ? nil : o[3 * p + a]) + r[a];
        }
        cross3(wp, z, t1);
        for (int a = 0; a < 3; ++a) {
            if (kind[k] == 1) {
                w[3 * k + a] = wp[a];
                dw[3 * k + a] = dwp[a];
                acc[3 * k + a] += 2.0 * t1[a] * qd + z[a] * qdd;
            } else {
                w[3 * k + a] = wp[a] + z[a] * qd;
                dw[3 * k + a] = dwp[a] + z[a] * qdd + t1[a] * qd;
            }
        }
    }
    std::fill(ws.force.begin(), ws.force.end(), nil);
    std::fill(ws.moment.begin(), ws.moment.end(), nil);
    for (int64_t k = F - 1; k >= 0; --k) {
        const double m = mass[k];
        const vd* Rk = &R[9 * k];
        vd *wk = &w[3 * k], *dwk = &dw[3 * k], *ak = &acc[3 * k], *fk = &force[3 * k], *mk = &moment[3 * k];
        if (m > 0.0) {
            const double* ck = com + 3 * k;
            const double* Ik = inertia + 9 * k;
            for (int a = 0; a < 3; ++a) c[a] = Rk[3 * a] * ck[0] + Rk[3 * a + 1] * ck[1] + Rk[3 * a + 2] * ck[2];
            for (int a = 0; a < 3; ++a)  // I = (R inertia) R^T
                for (int f = 0; f < 3; ++f)
                    RI[3 * a + f] = Rk[3 * a] * Ik[f] + Rk[3 * a + 1] * Ik[3 + f] + Rk[3 * a + 2] * Ik[6 + f];
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b)
                    I[3 * a + b] = RI[3 * a] * Rk[3 * b] + RI[3 * a + 1] * Rk[3 * b + 1] + RI[3 * a + 2] * Rk[3 * b + 2];
            cross3(wk, c, t1);
            cross3(wk, t1, t2);
            cross3(dwk, c, t1);
            for (int a = 0; a < 3; ++a) fk[a] += m * (ak[a] + t1[a] + t2[a]);
            for (int a = 0; a < 3; ++a) {  // t1 = I w, t2 = I dw
                t1[a] = I[3 * a] * wk[0] + I[3 * a + 1] * wk[1] + I[3 * a + 2] * wk[2];
                t2[a] = I[3 * a] * dwk[0] + I[3 * a + 1] * dwk[1] + I[3 * a + 2] * dwk[2];
            }
            cross3(wk, t1, z);
            cross3(c, ak, t1);
            for (int a = 0; a < 3; ++a) mk[a] += t2[a] + z[a] + m * t1[a];
        }
        const vd* v = kind[k] == 1 ? fk : mk;
        ws.tau[qidx[k]] = Rk[2] * v[0] + Rk[5] * v[1] + Rk[8] * v[2];
        const int64_t p = parent[k];
        if (p >= 0) {
            for (int a = 0; a < 3; ++a) r[a] = o[3 * k + a] - o[3 * p + a];
            cross3(r, fk, t1);
            for (int a = 0; a < 3; ++a) {
                force[3 * p + a] += fk[a];
                moment[3 * p + a] += mk[a] + t1[a];
            }
        }
    }
}

// tau (N, nq) = RNEA of the chain (frames in topological order; KR (F, 3, 3), Kp (F, 3), kind 1
// prismatic else revolute about z, qidx the frame's coordinate) with lumped masses mass (F,),
// centres of mass com (F, 3) and rotational inertias inertia (F, 3, 3) in the frames, the base
// accelerating at a_world (3,) (-gravity), for Q, V, A (N, nq) row-major. W samples per pass
// (rnea_lanes; the last pass fills its spare lanes with the last sample).
inline void rnea(int64_t F, const int64_t* parent, const double* KR, const double* Kp, const int64_t* kind,
                 const int64_t* qidx, const double* mass, const double* com, const double* inertia,
                 const double* a_world, const double* Q, const double* V, const double* A, int64_t N, int64_t nq,
                 double* tau) {
    if (N <= 0) return;
    RneaWork ws(F, nq);
    for (int64_t n0 = 0; n0 < N; n0 += W) {
        for (int l = 0; l < W; ++l) {
            const int64_t n = std::min(n0 + l, N - 1);
            for (int64_t j = 0; j < nq; ++j)
                ws.q[j][l] = Q[n * nq + j], ws.qd[j][l] = V[n * nq + j], ws.qdd[j][l] = A[n * nq + j];
        }
        rnea_lanes(F, parent, KR, Kp, kind, qidx, mass, com, inertia, a_world, ws);
        for (int l = 0; l < W && n0 + l < N; ++l)
            for (int64_t j = 0; j < nq; ++j) tau[(n0 + l) * nq + j] = ws.tau[j][l];
    }
}

// The halving loop of drake_mh/trajectories/bound.py kinematic_bound: B (P, n1, nq) Bernstein
// coefficients of the pieces, V (Pv, m, nq) values seen, centre / half (nq,) the ratio's, best
// (nq,) the largest ratio seen; left / right (n1, n1) de Casteljau's halves. certified (nq,): the
// bound. x / 0 is inf as in numpy (a joint without range: half inf gives 0).
inline void bernstein_bound(const double* B0, int64_t P0, int64_t n1, int64_t nq, const double* V, int64_t Pv,
                            int64_t m, const double* centre, const double* half, const double* best0, double slack,
                            int64_t max_levels, const double* left, const double* right, double* certified) {
    std::vector<double> best(best0, best0 + nq), B(B0, B0 + P0 * n1 * nq), bound, halves;
    auto ratio = [&](double x, int64_t j) { return std::max(x - centre[j], centre[j] - x) / half[j]; };
    for (int64_t j = 0; j < nq; ++j) certified[j] = -INFINITY;
    for (int64_t i = 0; i < Pv * m; ++i)
        for (int64_t j = 0; j < nq; ++j) best[j] = std::max(best[j], ratio(V[i * nq + j], j));
    int64_t P = P0;
    std::vector<int64_t> keep;
    for (int64_t level = 0; level <= max_levels && P > 0; ++level) {
        bound.assign(P * nq, 0.0);
        for (int64_t p = 0; p < P; ++p)
            for (int64_t j = 0; j < nq; ++j) {
                double lo = B[(p * n1) * nq + j], hi = lo;
                for (int64_t i = 1; i < n1; ++i) {
                    const double b = B[(p * n1 + i) * nq + j];
                    lo = std::min(lo, b), hi = std::max(hi, b);
                }
                bound[p * nq + j] = std::max(hi - centre[j], centre[j] - lo) / half[j];
            }
        keep.clear();
        for (int64_t p = 0; p < P; ++p) {
            bool open = false;
            if (level < max_levels)
                for (int64_t j = 0; j < nq; ++j) open |= bound[p * nq + j] > best[j] + slack;
            if (open)
                keep.push_back(p);
            else
                for (int64_t j = 0; j < nq; ++j) certified[j] = std::max(certified[j], bound[p * nq + j]);
        }
        const int64_t Kn = (int64_t)keep.size();
        halves.assign(2 * Kn * n1 * nq, 0.0);
        for (int64_t q = 0; q < Kn; ++q) {
            const double* Bp = &B[keep[q] * n1 * nq];
            for (int64_t i = 0; i < n1; ++i)
                for (int64_t j = 0; j < nq; ++j) {
                    double acc_l = 0.0, acc_r = 0.0;
                    for (int64_t k = 0; k < n1; ++k) {
                        acc_l += left[i * n1 + k] * Bp[k * nq + j];
                        acc_r += right[i * n1 + k] * Bp[k * nq + j];
                    }
                    halves[(q * n1 + i) * nq + j] = acc_l;
                    halves[((Kn + q) * n1 + i) * nq + j] = acc_r;
                }
        }
        for (int64_t p = 0; p < 2 * Kn; ++p)  // the halves' end values: exact values of the polynomial
            for (int64_t i : {int64_t(0), n1 - 1})
                for (int64_t j = 0; j < nq; ++j) best[j] = std::max(best[j], ratio(halves[(p * n1 + i) * nq + j], j));
        B.swap(halves);
        P = 2 * Kn;
    }
    for (int64_t j = 0; j < nq; ++j) certified[j] = std::max(certified[j], best[j]);
}

}  // namespace dmh
