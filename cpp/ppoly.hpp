// Piecewise polynomials as scipy.interpolate.PPoly stores them, and the chain rule of a timed path
// q(t) = p(s(t)): the answers of drake_mh/trajectories/trajectory.py Trajectory.derivatives.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace dmh {

// A piecewise polynomial: breaks x (m + 1,) increasing, coefficients c (k + 1, m, d) row-major,
// highest power first (scipy's PPoly layout): on [x_i, x_{i+1}) the value is
// sum_j c[j, i, :] (t - x_i)^(k - j).
struct PPoly {
    const double* c;
    const double* x;
    int64_t k, m, d;

    // scipy's find_interval with extrapolation: x_i <= t < x_{i+1}, the last piece at and past
    // the end, the first before the start
    int64_t piece(double t) const {
        const double* it = std::upper_bound(x, x + m + 1, t);
        int64_t i = (int64_t)(it - x) - 1;
        return i < 0 ? 0 : (i > m - 1 ? m - 1 : i);
    }
};

// p (order + 1, d): derivatives 0..order of every component at t in piece i (inner loops run
// over the contiguous components, so they vectorize)
inline void ppoly_derivatives(const PPoly& pp, int64_t i, double t, int order, double* p) {
    const double y = t - pp.x[i];
    const int64_t d = pp.d;
    for (int r = 0; r <= order; ++r) {
        double* pr = p + r * d;
        for (int64_t e = 0; e < d; ++e) pr[e] = 0.0;
        if (r > pp.k) continue;
        double y_power = 1.0;  // y^(k - j - r), from the lowest power up
        for (int64_t j = pp.k - r; j >= 0; --j) {
            const int64_t power = pp.k - j;
            double factor = y_power;
            for (int q = 0; q < r; ++q) factor *= (double)(power - q);
            const double* cj = pp.c + (j * pp.m + i) * d;
            for (int64_t e = 0; e < d; ++e) pr[e] += cj[e] * factor;
            y_power *= y;
        }
    }
}

// out (order + 1, M, nq): [q, q', ..., q^(order)] of q(t) = p(s(t)) at times T (M,), with path p
// (d = nq) and timing s (d = 1); timing.c == nullptr: q = p(t). Chain rule:
//   q' = p' s',  q'' = p'' s'^2 + p' s'',  q''' = p''' s'^3 + 3 p'' s' s'' + p' s'''.
inline void timed_derivatives(const PPoly& path, const PPoly& timing, const double* T, int64_t M, int order,
                              double* out) {
    const int64_t nq = path.d, stride = M * nq;
    std::vector<double> p((size_t)(4 * nq));
    for (int64_t n = 0; n < M; ++n) {
        double s[4] = {T[n], 1.0, 0.0, 0.0};
        if (timing.c != nullptr) ppoly_derivatives(timing, timing.piece(T[n]), T[n], order, s);
        ppoly_derivatives(path, path.piece(s[0]), s[0], order, p.data());
        const double *p0 = p.data(), *p1 = p0 + nq, *p2 = p1 + nq, *p3 = p2 + nq;
        double* o = out + n * nq;
        for (int64_t e = 0; e < nq; ++e) o[e] = p0[e];
        if (timing.c == nullptr) {
            for (int r = 1; r <= order; ++r)
                for (int64_t e = 0; e < nq; ++e) o[r * stride + e] = p[r * nq + e];
            continue;
        }
        const double s1 = s[1], s2 = s[2], s3 = s[3];
        if (order >= 1)
            for (int64_t e = 0; e < nq; ++e) o[stride + e] = p1[e] * s1;
        if (order >= 2)
            for (int64_t e = 0; e < nq; ++e) o[2 * stride + e] = p2[e] * (s1 * s1) + p1[e] * s2;
        if (order >= 3)
            for (int64_t e = 0; e < nq; ++e)
                o[3 * stride + e] = p3[e] * (s1 * s1 * s1) + 3.0 * p2[e] * (s1 * s2) + p1[e] * s3;
    }
}

}  // namespace dmh
